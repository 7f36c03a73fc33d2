"""CrowdParams overrides as the study scripts' ``--set FIELD=VALUE`` give them."""

import pytest

from crowdwalk.crowd import CrowdParams
from crowdwalk.crowd.params import crowd_model, parse_overrides


def test_set_texts_become_values_and_replace_own_and_steering_fields():
    fields = parse_overrides(["speed_model=headway", "headway_lane=1.233", "line_up=True",
                              "steering.twists_deg=(45.0,)"])
    assert fields == {"speed_model": "headway", "headway_lane": 1.233, "line_up": True,
                      "steering.twists_deg": (45.0,)}
    base = crowd_model("free")
    params = base.with_overrides(fields)
    assert (params.speed_model, params.headway_lane, params.line_up) == ("headway", 1.233, True)
    assert params.steering.twists_deg == (45.0,)
    assert base.steering.twists_deg == (60.0,) and base.speed_model == "free"
    assert params.steering.wall_weight == base.steering.wall_weight


def test_an_unknown_field_is_refused():
    with pytest.raises(TypeError):
        CrowdParams().with_overrides({"no_such_field": 1})
    with pytest.raises(TypeError):
        CrowdParams().with_overrides({"steering.no_such_field": 1})


def test_named_crowd_models_set_their_fields_and_overrides_go_on_top():
    from crowdwalk.crowd.params import CROWD_MODELS
    from crowdwalk.errors import InputError

    s175 = crowd_model("headway_s175")
    assert s175 == CrowdParams()  # the default
    assert s175.speed_model == "headway" and s175.headway_route_lane and s175.line_up
    free = crowd_model("free")
    assert free.speed_model == "free" and not free.headway_route_lane and not free.line_up
    changed = {k for k in vars(s175) if getattr(free, k) != getattr(s175, k)}
    assert changed == set(CROWD_MODELS["free"])  # every switch its own field
    mixed = crowd_model("headway_s175", {"headway_lane": 2.0, "steering.right_bias": 0.0})
    assert (mixed.headway_lane, mixed.steering.right_bias, mixed.line_up) == (2.0, 0.0, True)
    with pytest.raises(InputError, match="crowd.model must be one of free, headway_s175"):
        crowd_model("fast")

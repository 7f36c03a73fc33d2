"""The run folder: round trip, PedPy reads the trajectory file unchanged, a killed writer
leaves readable files."""

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

from crowdwalk.errors import InputError
from crowdwalk.record import FOOTSTEP_COLUMNS, FootstepTable, RunWriter, open_run

SQUARE = "POLYGON ((0 0, 10 0, 10 5, 0 5, 0 0))"


def _steps(k, t0=0.0):
    rows = {c: np.zeros(k) for c in FOOTSTEP_COLUMNS}
    rows["agent"] = np.arange(k)
    rows["step"] = np.arange(k) + 1
    rows["time"] = t0 + np.linspace(0, 1, k)
    rows["foot"] = np.array(["left", "right"] * (k // 2) + ["left"] * (k % 2))
    rows["planner"] = np.array(["best_first"] * k)
    rows["group"] = np.array(["g"] * k)
    rows["x"] = np.linspace(1, 2, k)
    rows["kind"] = np.zeros(k, int)
    rows["on_obstacle"] = np.zeros(k, int)
    return rows


def _write(tmp_path, poses=True):
    skeleton = (["root", "l_hip", "l_knee"], [-1, 0, 1]) if poses else None
    w = RunWriter(tmp_path, scenario_text="name: t\n", walkable_wkt=SQUARE, fps=10.0,
                  skeleton=skeleton)
    rng = np.random.default_rng(1)
    for frame in range(5):
        ids = np.array([3, 7]) if frame < 4 else np.array([7])
        xy = rng.uniform(1, 4, (ids.size, 2))
        ori = np.tile([1.0, 0.0], (ids.size, 1))
        w.write_frame(frame, ids, xy, z=np.full(ids.size, 0.25 * frame), orientation=ori)
        if poses:
            k = ids.size
            w.write_pose(frame, frame / 10, ids, xy @ np.eye(2, 3), np.tile([1, 0, 0, 0], (k, 1)),
                         np.tile([1.0, 0, 0, 0], (k, 3, 1)), rng.normal(size=(k, 3, 3)),
                         np.ones((k, 2), bool), np.zeros(k, bool))
    w.write_agents(np.array([3, 7]), np.array([1.7, 1.8]), ["g", "g"], ["fixed", "fixed"])
    w.write_footsteps(_steps(3))
    w.write_summary({"agents": {"3": {"distance": np.float64(2.5)}}, "complete": True})
    w.close()
    return rng


def test_round_trip(tmp_path):
    _write(tmp_path)
    run = open_run(tmp_path)
    traj = run.trajectories()
    assert traj.frame.tolist() == [0, 0, 1, 1, 2, 2, 3, 3, 4]
    assert traj.id.tolist() == [3, 7] * 4 + [7]
    np.testing.assert_allclose(traj.z, np.repeat([0, 0.25, 0.5, 0.75], 2).tolist() + [1.0])
    assert run.fps == 10.0
    assert run.walkable_area().area == pytest.approx(50.0)
    steps = run.footsteps()
    assert steps.agent.tolist() == [0, 1, 2]
    assert steps.foot.tolist() == ["left", "right", "left"]
    np.testing.assert_allclose(steps.x, [1, 1.5, 2])
    assert run.summary["agents"]["3"]["distance"] == 2.5
    poses = run.poses()
    assert poses.names == ["root", "l_hip", "l_knee"]
    assert poses.parents.tolist() == [-1, 0, 1]
    assert poses.frames.tolist() == [0, 1, 2, 3, 4]
    rec = poses.frame(4)
    assert rec.ids.tolist() == [7] and rec.joints.shape == (1, 3, 4)
    track = poses.agent_track(3)
    assert track["time"].shape == (4,) and track["positions"].shape == (4, 3, 3)
    assert poses.body_heights == {3: 1.7, 7: 1.8}
    assert _indices(tmp_path) == ["frame_id_idx"]  # built when the writer closed


def _indices(run_dir) -> list[str]:
    import sqlite3
    from contextlib import closing

    with closing(sqlite3.connect(run_dir / "trajectories.sqlite")) as con:
        return [r[0] for r in con.execute("SELECT name FROM sqlite_master WHERE type='index' "
                                          "AND tbl_name='trajectory_data'")]


def test_frames_of_many_walkers_keep_every_row_in_order(tmp_path):
    """Rows go in by multi-row INSERTs of _ROWS_PER_INSERT rows and one of the rest."""
    from crowdwalk.record import _ROWS_PER_INSERT

    rng = np.random.default_rng(3)
    w = RunWriter(tmp_path, scenario_text="", walkable_wkt=SQUARE, fps=10.0)
    sizes = [2 * _ROWS_PER_INSERT + 7, _ROWS_PER_INSERT, 1, _ROWS_PER_INSERT - 1]
    frames = []
    for f, k in enumerate(sizes):
        ids = np.sort(rng.choice(10**6, k, replace=False))
        xy, z = rng.uniform(0, 5, (k, 2)), rng.uniform(-1, 1, k)
        ang = rng.uniform(-np.pi, np.pi, k)
        ori = np.column_stack([np.cos(ang), np.sin(ang)])
        w.write_frame(f, ids, xy, z, ori)
        frames.append((np.full(k, f), ids, xy, z, ori))
    w.close()
    traj = open_run(tmp_path).trajectories()
    f, ids, xy, z, ori = (np.concatenate(c) for c in zip(*frames, strict=True))
    assert traj.frame.tolist() == f.tolist() and traj.id.tolist() == ids.tolist()
    assert np.array_equal(np.column_stack([traj.x, traj.y]), xy)  # bit for bit
    assert np.array_equal(traj.z, z)
    assert np.array_equal(np.column_stack([traj.ori_x, traj.ori_y]), ori)
    with pytest.raises(ValueError, match="RunWriter.frame"):
        RunWriter(tmp_path / "bad", scenario_text="", walkable_wkt=SQUARE,
                  fps=10.0).write_frame(0, np.arange(3), np.zeros((2, 2)), np.zeros(3),
                                        np.zeros((3, 2)))


def test_pedpy_reads_trajectory_unchanged(tmp_path):
    pedpy = pytest.importorskip("pedpy")
    _write(tmp_path, poses=False)
    path = tmp_path / "trajectories.sqlite"
    traj = pedpy.load_trajectory_from_jupedsim_sqlite(trajectory_file=path)
    assert traj.frame_rate == 10.0
    assert len(traj.data) == 9
    assert set(traj.data["id"]) == {3, 7}
    area = pedpy.load_walkable_area_from_jupedsim_sqlite(trajectory_file=path)
    assert area.polygon.area == pytest.approx(50.0)
    assert not (tmp_path / "poses.sqlite").exists()
    assert open_run(tmp_path).poses() is None


def test_footsteps_need_every_column(tmp_path):
    w = RunWriter(tmp_path, scenario_text="", walkable_wkt=SQUARE, fps=5)
    rows = _steps(2)
    del rows["energy"]
    with pytest.raises(ValueError, match="RunWriter.footsteps must be"):
        w.write_footsteps(rows)
    w.close()


def test_footsteps_read_back_as_a_typed_frozen_table(tmp_path):
    _write(tmp_path)
    steps = open_run(tmp_path).footsteps()
    assert isinstance(steps, FootstepTable) and len(steps) == 3
    assert steps.agent.dtype.kind == "i" and steps.kind.dtype.kind == "i"
    assert steps.foot.dtype.kind == "U" and steps.energy.dtype.kind == "f"
    with pytest.raises(AttributeError):
        steps.x = np.zeros(3)  # frozen
    one = steps.of_agent(1)
    assert len(one) == 1 and one.x.tolist() == [1.5] and one.foot.tolist() == ["right"]
    with pytest.raises(ValueError, match="FootstepTable.x"):
        FootstepTable(**{**steps.columns(), "x": np.zeros(2)})  # ragged


def test_footsteps_text_is_what_csv_writer_writes(tmp_path):
    """write_footsteps joins the rows itself; the bytes are csv.writer's (str of each
    value rounded to 5 decimals, quoting, \\r\\n), also for nan, inf, -0.0, 1e-05, 1e+16
    and names csv must quote."""
    import csv
    import io

    rng = np.random.default_rng(7)
    batches = []
    for names in (["g", "section_0"], ['a,b', 'say "hi"'], ["x", "line\nbreak"]):
        rows = _steps(40)
        for c in ("x", "y", "z", "energy", "heading", "spin"):
            v = rng.normal(0, 10.0 ** rng.integers(-7, 18, 40))
            v[::7], v[1::11], v[2::13], v[3::5] = np.nan, np.inf, -0.0, 1e-5
            rows[c] = v
        rows["group"] = np.array(names * 20)
        rows["on_obstacle"] = rng.integers(0, 2, 40)
        batches.append(rows)
    w = RunWriter(tmp_path, scenario_text="", walkable_wkt=SQUARE, fps=10.0)
    want = io.StringIO(newline="")
    ref = csv.writer(want)
    ref.writerow(FOOTSTEP_COLUMNS)
    for rows in batches:
        w.write_footsteps(rows)
        ref.writerows(zip(*[np.round(r, 5).tolist() if np.asarray(r).dtype.kind == "f"
                            else np.asarray(r).tolist()
                            for r in (rows[c] for c in FOOTSTEP_COLUMNS)], strict=True))
    w.write_footsteps({c: np.zeros(0) for c in FOOTSTEP_COLUMNS})  # no rows: no line
    w.close()
    assert (tmp_path / "footsteps.csv").read_bytes() == want.getvalue().encode()
    steps = open_run(tmp_path).footsteps()
    assert steps.group.tolist()[40:42] == ['a,b', 'say "hi"']
    rows = _steps(3)
    rows["x"] = np.zeros(2)
    with pytest.raises(ValueError, match="RunWriter.footsteps must be columns of one length"):
        RunWriter(tmp_path / "b", scenario_text="", walkable_wkt=SQUARE,
                  fps=10.0).write_footsteps(rows)


def test_footsteps_of_old_and_broken_files(tmp_path):
    _write(tmp_path)
    path = tmp_path / "footsteps.csv"
    lines = path.read_text().splitlines()
    header = lines[0].split(",")
    keep = [k for k, c in enumerate(header) if c not in ("toe_out", "spin")]
    path.write_text("\n".join(",".join(line.split(",")[k] for k in keep)
                               for line in lines) + "\n")
    steps = open_run(tmp_path).footsteps()  # written before MetaGait's columns: NaN
    assert np.isnan(steps.spin).all() and np.isnan(steps.toe_out).all()
    np.testing.assert_allclose(steps.x, [1, 1.5, 2])
    path.write_text(lines[0].replace("energy,", "") + "\n")
    with pytest.raises(InputError, match=r"footsteps.csv:1: .*'energy'"):
        open_run(tmp_path).footsteps()


def test_bad_fps_is_rejected(tmp_path):
    with pytest.raises(ValueError, match=r"RunWriter.fps must be a positive frame rate \[1/s\]"):
        RunWriter(tmp_path, scenario_text="", walkable_wkt=SQUARE, fps=0)


def test_killed_writer_leaves_readable_files(tmp_path):
    """A writer killed (SIGKILL) between flushes leaves everything up to the last flush."""
    script = textwrap.dedent(
        f"""
        import sys, time
        import numpy as np
        from crowdwalk.record import RunWriter, FOOTSTEP_COLUMNS
        w = RunWriter(sys.argv[1], scenario_text="x: 1\\n", walkable_wkt={SQUARE!r}, fps=10,
                      skeleton=(["root"], [-1]))
        for frame in range(10**6):
            w.write_frame(frame, np.array([1]), np.array([[1.0, 1.0]]), np.zeros(1),
                          np.array([[1.0, 0.0]]))
            w.write_pose(frame, frame / 10, np.array([1]), np.zeros((1, 3)),
                         np.array([[1.0, 0, 0, 0]]), np.zeros((1, 1, 4)), np.zeros((1, 1, 3)),
                         np.ones((1, 2), bool), np.zeros(1, bool))
            rows = {{c: np.zeros(1) for c in FOOTSTEP_COLUMNS}}
            rows.update(foot=np.array(["left"]), planner=np.array(["fixed"]),
                        group=np.array(["g"]))
            w.write_footsteps(rows)
            if frame % 10 == 9:
                w.flush()
                print(frame, flush=True)
            time.sleep(0.002)
        """
    )
    proc = subprocess.Popen([sys.executable, "-c", script, str(tmp_path)], stdout=subprocess.PIPE,
                            text=True)
    try:
        for _ in range(3):  # wait for three flushes
            assert proc.stdout.readline().strip()
        time.sleep(0.05)
    finally:
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
    run = open_run(tmp_path)
    traj = run.trajectories()
    assert traj.frame.size >= 30
    assert np.array_equal(traj.frame, np.arange(traj.frame.size))
    assert run.poses().frames.size >= 30
    assert run.footsteps().agent.size >= 30
    assert _indices(tmp_path) == []  # the index is built at close: killed, none
    pedpy = pytest.importorskip("pedpy")
    assert len(pedpy.load_trajectory_from_jupedsim_sqlite(
        trajectory_file=tmp_path / "trajectories.sqlite").data) >= 30


SCENARIO = Path(__file__).parents[1] / "scenarios" / "counterflow.yaml"


def _start_run(out):
    return subprocess.Popen(
        [sys.executable, "-m", "crowdwalk.cli", "run", str(SCENARIO), "--out", str(out),
         "--quiet"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _wait_for_frames(out, proc, frames: int, timeout: float = 60.0) -> None:
    import sqlite3

    start = time.monotonic()
    while time.monotonic() - start < timeout:
        assert proc.poll() is None, proc.stderr.read()
        path = out / "trajectories.sqlite"
        if path.exists():
            try:
                with sqlite3.connect(f"file:{path}?mode=ro", uri=True) as con:
                    n = con.execute("SELECT MAX(frame) FROM trajectory_data").fetchone()[0]
            except sqlite3.OperationalError:
                n = None
            if n is not None and n >= frames:
                return
        time.sleep(0.2)
    raise AssertionError("the run did not write frames in time")


def test_killed_crowdwalk_run_stays_readable(tmp_path):
    """SIGKILL mid-run: everything up to the last flush (once per simulated second)."""
    proc = _start_run(tmp_path)
    try:
        _wait_for_frames(tmp_path, proc, frames=25)  # 2.5 s simulated at 10 fps
    finally:
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
    run = open_run(tmp_path)
    assert not run.complete  # no summary.json: readers name the folder an incomplete run
    traj = run.trajectories()
    assert traj.frame.max() >= 20 and len(np.unique(traj.id)) >= 2
    steps = run.footsteps()
    assert steps.agent.size > 0 and np.isfinite(steps.x).all()
    assert _indices(tmp_path) == []
    pedpy = pytest.importorskip("pedpy")
    data = pedpy.load_trajectory_from_jupedsim_sqlite(
        trajectory_file=tmp_path / "trajectories.sqlite")
    assert len(data.data) == traj.frame.size


def test_interrupted_crowdwalk_run_exits_130_with_a_summary(tmp_path):
    proc = _start_run(tmp_path)
    try:
        _wait_for_frames(tmp_path, proc, frames=15)
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 130
    assert "Traceback" not in err and "interrupted" in err
    summary = open_run(tmp_path).summary
    assert summary["interrupted"] is True and summary["complete"] is False
    assert _indices(tmp_path) == ["frame_id_idx"]  # the interrupted writer closed
    assert 1.0 <= summary["simulated_time_s"] < 70.0


def test_a_signal_within_a_run_waits_for_the_tick_boundary():
    """SIGINT only requests a stop; it is raised where the loop checks, not mid-callback."""
    from crowdwalk import interrupts

    reached = False
    with pytest.raises(KeyboardInterrupt):
        with interrupts.deferred():
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.05)
            reached = True
            interrupts.check()
            reached = False
    assert reached
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler

"""Shared strategies and fixtures for the planner tests."""

import pytest

from planners import Leg


@pytest.fixture(scope="session")
def leg():
    return Leg.from_body_height(1.75)

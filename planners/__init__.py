"""Footstep planners on a ground profile (Chen & Li). Depends on numpy/scipy only."""

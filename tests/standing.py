"""The normal forces on a bicycle standing still, for the contact engines' tests (DART's run
world, Drake's contact plant): statics from the reference's points, independent of any
engine."""

import numpy as np

__all__ = ["static_split"]


def static_split(model, q=None):
    """(rear, front) normal forces (N) on the bicycle standing upright and still at ``q``
    (default all zeros): vertical balance N_C + N_D = m g and moments about the rear contact C
    along the pitch axis, N_D l = m g x_G (x_G the total CoM's distance ahead of C, l the
    wheelbase, both from the reference's points; the horizontal contact forces act at ground
    level on the line through C and give no moment about it)."""
    p, pts = model.params, model.points(np.zeros(8) if q is None else q)
    masses = {b: getattr(p, f"m{b}") for b in (2, 3, 4, 5)}
    m = sum(masses.values())
    x_G = sum(mb * (pts[f"rG{b}"][0] - pts["rC"][0]) for b, mb in masses.items()) / m
    l = pts["rD"][0] - pts["rC"][0]
    front = m * p.g * x_G / l
    return m * p.g - front, front

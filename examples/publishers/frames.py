"""motormix reads attitude in body FRD (x front, y right, z down) relative to
NED (north, east, down). Estimators built for ROS and many SLAM stacks give
body FLU (x front, y left, z up) relative to ENU (east, north, up). These are
the conversions, in one place; take them if your estimator is FLU/ENU."""

import math


def multiply(a, b):
    """Hamilton product of two quaternions (w, x, y, z)."""
    return (
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    )


def frd_ned_from_flu_enu(q_enu_flu):
    """q rotating body FLU into ENU -> q rotating body FRD into NED.

    ENU -> NED swaps the first two axes and negates the third (180 degrees
    about (1, 1, 0)/sqrt 2); FRD -> FLU negates y and z (180 degrees about x).
    """
    h = math.sqrt(0.5)
    return multiply(multiply((0.0, h, h, 0.0), q_enu_flu), (0.0, 1.0, 0.0, 0.0))


def frd_from_flu(v):
    """Body rates (or any body vector) FLU -> FRD: y and z change sign."""
    return (v[0], -v[1], -v[2])


def ned_from_enu(v):
    """Velocity ENU -> NED: north is ENU's y, east its x, down minus its z."""
    return (v[1], v[0], -v[2])

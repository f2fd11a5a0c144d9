"""The lateral path of a lane change: a minimum-jerk (quintic) profile in time.

    r(t) = r0 + (r1 - r0) (10 τ^3 - 15 τ^4 + 6 τ^5),   τ = t / duration in [0, 1]

The quintic that starts and ends at rest with zero lateral acceleration minimises the
integrated squared jerk (Flash and Hogan 1985), the usual model of a smooth human manoeuvre;
its lateral speed peaks at mid-change at 1.875 |r1 - r0| / duration (15/8: the derivative
30 τ^2 - 60 τ^3 + 30 τ^4 at τ = 1/2). A change of one lane (3.5 m) takes 3-4 s in normal
driving; MOBIL's changes take DEFAULT_CHANGE_DURATION_S, a scripted cut-in its own duration.
"""

from __future__ import annotations

DEFAULT_CHANGE_DURATION_S = 4.0
PEAK_SPEED_FACTOR = 1.875  # peak |dr/dt| = PEAK_SPEED_FACTOR |r1 - r0| / duration


def _progress(duration_s: float, t_s: float) -> float:
    """τ, clamped to [0, 1]: before its start the path is at r0, after its end at r1."""
    if duration_s <= 0.0:
        raise ValueError(f"a lane change needs a duration > 0 s, got {duration_s}")
    return min(1.0, max(0.0, t_s / duration_s))


def lateral_offset(r0: float, r1: float, duration_s: float, t_s: float) -> float:
    """r (m) at `t_s` seconds after the start of a change from r0 to r1."""
    tau = _progress(duration_s, t_s)
    # r0 + (r1 - r0) τ^3 (10 - 15 τ + 6 τ^2)
    return r0 + (r1 - r0) * tau**3 * (10.0 + tau * (-15.0 + 6.0 * tau))


def lateral_speed(r0: float, r1: float, duration_s: float, t_s: float) -> float:
    """dr/dt (m/s) at `t_s` seconds after the start; 0 before the start and after the end."""
    tau = _progress(duration_s, t_s)
    # (r1 - r0) / duration * 30 τ^2 (1 - τ)^2
    return (r1 - r0) / duration_s * 30.0 * tau**2 * (1.0 - tau) ** 2

"""The acceleration severity index of EN 1317-1 (the 2010 edition, and the 1998 one).

    ASI(t) = sqrt((a_x / 12 g)^2 + (a_y / 9 g)^2 + (a_z / 10 g)^2),   ASI = max ASI(t),

with g = 9.80665 m/s^2 and the vehicle's acceleration components conditioned as the edition
says: EN 1317-1:2010, a four-pole phaseless Butterworth low-pass at 13 Hz on the record padded
by 0.5 s at each end (`barrierjax.assess.filters`); EN 1317-1:1998, a 50 ms moving average.
The 2010 filter overshoots a steep step by 1 + exp(-3 pi / 4) / (2 sqrt 2) = 1.0335 (the
step response of two passes of the 2-pole Butterworth), so a short rectangular pulse's ASI
can exceed its plateau's; a pulse whose ramps are long against 1 / 13 Hz tends to the
plateau's value (tests/test_assess.py measures both).
"""

import jax.numpy as jnp

from . import filters, signals
from .matrices import G

__all__ = ["ASI_LIMITS", "ASI_PAD_SECONDS", "asi_history", "conditioned_accelerations"]

ASI_LIMITS = (12.0 * G, 9.0 * G, 10.0 * G)  # m/s^2: x, y, z (EN 1317-1)
ASI_PAD_SECONDS = 0.5  # EN 1317-1:2010: the record padded by 0.5 s at each end
ASI_AVERAGE_1998 = 0.050  # s: EN 1317-1:1998's moving average

EDITIONS = ("2010", "1998")


def conditioned_accelerations(a, dt, edition: str = "2010", end=None):
    """The acceleration components `a` (..., 3, n) as the ASI of `edition` reads them (the
    record ends at `end`, default its last sample; zeros after it)."""
    if edition == "2010":
        return filters.zero_padded_lowpass(a, dt, filters.ASI_CUTOFF, pad_seconds=ASI_PAD_SECONDS)
    if edition == "1998":
        return filters.moving_average(a, dt, ASI_AVERAGE_1998, end)
    raise ValueError(f"asi_edition must be one of {EDITIONS}; got {edition!r}")


def asi_history(ax, ay, az, dt, edition: str = "2010", end=None):
    """ASI(t) at every sample of one record (arrays of n samples at step `dt`; `az` None
    for none; the record ends at `end`, default its last sample, zeros after it)."""
    channels = [ax, ay] if az is None else [ax, ay, az]
    conditioned = conditioned_accelerations(jnp.stack(channels), dt, edition, end)
    limits = jnp.asarray(ASI_LIMITS[: len(channels)], dtype=conditioned.dtype)[:, None]
    return signals.safe_norm(conditioned / limits, axis=0)

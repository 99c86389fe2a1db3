"""Kinematic deficits laid over a recorded trajectory (not acted): slowed playback, tremor, drift of the view,
pauses, and going back over the path already covered.

Where a family of fastrl.data.families deviates in how a trainee acts, these deform what was recorded, as a person
who builds a cohort from recordings would; replay then decides what the deformed motion achieves. Each takes a
severity g (0: the trajectory unchanged) and a generator, and returns coordinates on the same control grid."""

from __future__ import annotations

import numpy as np

JITTER_HZ = (3.0, 8.0)  # physiological tremor band
JITTER = np.array([0.8, 0.8, 0.0015, 2.0, 0.0])  # rms at g = 1: pitch, yaw (deg), insertion (m), roll (deg), cable
DRIFT = np.array([3.0, 3.0, 0.008, 8.0, 0.0])  # rms of the slow drift at g = 1, same units
DRIFT_S = 1.5  # correlation time of the drift (s)
PAUSED = 0.5  # at g = 1 the holds add half the recording's duration
RETRACED = 0.3  # at g = 1 the stretches gone back over sum to 0.3 of it (each twice: undone, then done again)
EVENT_S = 4.0  # one pause or retraced stretch per 4 s of recording at g = 1, and at least one
DEG = np.array([np.pi / 180, np.pi / 180, 1.0, np.pi / 180, np.pi / 180])  # units above to portal units


def slowed(portal: np.ndarray, g: float, rng: np.random.Generator) -> np.ndarray:
    """The motion played back slower, at a speed that wanders between 1 / (1 + 2.5g) and 1 of the original."""
    if g <= 0:
        return portal
    n = len(portal)
    wander = np.convolve(rng.random(n * 4), np.ones(20) / 20, mode="same")  # smooth, in [0, 1]
    speed = 1.0 / (1.0 + 2.5 * g * (0.5 + wander))
    progress = np.concatenate([[0.0], np.cumsum(speed)])
    progress = np.append(progress[progress < n - 1], n - 1)  # ends where the recording ends
    return np.column_stack([np.interp(progress, np.arange(n), portal[:, j]) for j in range(portal.shape[1])])


def _band_noise(n: int, hz: float, band: tuple[float, float], rng: np.random.Generator) -> np.ndarray:
    """Unit-rms noise of n samples at `hz`, its spectrum inside `band` (Hz)."""
    spectrum = np.fft.rfft(rng.normal(size=n))
    f = np.fft.rfftfreq(n, 1.0 / hz)
    spectrum[(f < band[0]) | (f > band[1])] = 0.0
    x = np.fft.irfft(spectrum, n)
    sd = x.std()
    return x / sd if sd > 0 else x


def jittered(portal: np.ndarray, g: float, rng: np.random.Generator, hz: float) -> np.ndarray:
    """Tremor in the 3-8 Hz band on pitch, yaw, insertion and roll."""
    if g <= 0:
        return portal
    noise = np.column_stack([_band_noise(len(portal), hz, JITTER_HZ, rng) for _ in range(portal.shape[1])])
    return portal + g * noise * JITTER * DEG


def drifted(portal: np.ndarray, g: float, rng: np.random.Generator, hz: float) -> np.ndarray:
    """A slow random drift of the view (an Ornstein-Uhlenbeck process per coordinate) that the hand corrects late."""
    if g <= 0:
        return portal
    n, a = len(portal), np.exp(-1.0 / (DRIFT_S * hz))
    x = np.zeros((n, portal.shape[1]))
    shocks = rng.normal(size=x.shape) * np.sqrt(1 - a * a)
    for t in range(1, n):
        x[t] = a * x[t - 1] + shocks[t]
    return portal + g * x * DRIFT * DEG


def _events(n: int, g: float, share: float, hz: float, rng: np.random.Generator) -> list[tuple[int, int]]:
    """(sample, length in samples) of the events of a g-severe overlay: at least one, about one per EVENT_S / g
    seconds, at random moments, their lengths random shares of g * share of the recording."""
    k = 1 + rng.poisson(g * n / hz / EVENT_S)
    moments = np.sort(rng.integers(1, max(n, 2), k))
    lengths = np.round(rng.dirichlet(np.ones(k)) * g * share * n).astype(int)
    return list(zip(moments.tolist(), lengths.tolist()))


def paused(portal: np.ndarray, g: float, rng: np.random.Generator, hz: float) -> np.ndarray:
    """Stops mid-motion: at random moments the scope is held still, in all for g / 2 of the recording's duration."""
    if g <= 0:
        return portal
    pieces, last = [], 0
    for t, hold in _events(len(portal), g, PAUSED, hz, rng):
        pieces += [portal[last:t], np.repeat(portal[t - 1 : t], hold, axis=0)]
        last = t
    return np.concatenate([*pieces, portal[last:]])


def retraced(portal: np.ndarray, g: float, rng: np.random.Generator, hz: float) -> np.ndarray:
    """Going back over the path: at random moments the motion just made is undone and then done again."""
    if g <= 0:
        return portal
    pieces, last = [], 0
    for t, back in _events(len(portal), g, RETRACED, hz, rng):
        stretch = portal[max(t - back, last) : t]
        pieces += [portal[last:t], stretch[::-1], stretch]
        last = t
    return np.concatenate([*pieces, portal[last:]])


OVERLAYS = {"slowed": slowed, "jitter": jittered, "drift": drifted, "paused": paused, "retraced": retraced}


def overlaid(portal: np.ndarray, severities: dict[str, float], seed: int, hz: float, ranges: np.ndarray) -> np.ndarray:
    """The coordinates with each named overlay at its severity, in OVERLAYS order, kept inside the joint ranges."""
    rng = np.random.default_rng([seed, 7717])
    out = portal
    for name, fn in OVERLAYS.items():
        g = severities.get(name, 0.0)
        if g > 0:
            out = fn(out, g, rng) if name == "slowed" else fn(out, g, rng, hz)
    return np.clip(out, ranges[:, 0], ranges[:, 1])

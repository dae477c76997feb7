"""Convergence rates: level-to-level rates, the least-squares fitted rate, agreement with a
predicted exponent, and the monotone-until-floor test of a series.

A rate that needs a value that is not finite and positive is nan, with a note saying why."""
import math

import numpy as np

MONOTONE_RTOL = 1e-6     # slack of the monotone-decrease test e_k <= e_{k-1} (1 + MONOTONE_RTOL)
FLOOR_BAND = (0.5, 2.0)  # band around the floor value F that every later e must stay in


def invalid(value):
    """Why `value` cannot enter a logarithm ('' when it can: a finite number > 0)."""
    if not isinstance(value, (int, float)) or isinstance(value, bool):
        return "not a number"
    if not math.isfinite(value):
        return "not finite"
    if value <= 0:
        return "<= 0"
    return ""


def first_invalid(x, e, first_level, indices):
    """Note naming the first x or e among `indices` that cannot enter a logarithm ('' if none).

    Levels are numbered from `first_level` (the level of x[0]).
    """
    for name, values in (("x", x), ("e", e)):
        for j in indices:
            why = invalid(values[j])
            if why:
                return f"{name}_{first_level + j} {why}"
    return ""


def level_rates(x, e):
    """Level-to-level rates [(rate, note)] for levels 1.., rate = log(e_k/e_{k-1})/log(x_k/x_{k-1}).

    `note` is '' for a valid rate; otherwise rate is nan and note says why.
    """
    out = []
    for k in range(1, len(x)):
        note = first_invalid(x, e, 0, [k - 1, k])
        if not note and x[k] == x[k - 1]:
            note = f"x_{k} = x_{k - 1}"
        if note:
            out.append((math.nan, note))
        else:
            out.append((math.log(e[k] / e[k - 1]) / math.log(x[k] / x[k - 1]), ""))
    return out


def fitted_rate(x, e, first_level=0):
    """Least-squares slope of log e against log x over all given points: (rate, note).

    Every point must be finite and positive, else the rate is nan and the note names the first
    offending level (x[0] being level `first_level`); at least two distinct x are needed.
    """
    note = first_invalid(x, e, first_level, range(len(x)))
    if note:
        return math.nan, note
    lx, le = np.log(np.asarray(x, float)), np.log(np.asarray(e, float))
    dx = lx - lx.mean()
    sxx = float(dx @ dx)
    if sxx == 0.0:
        return math.nan, "fewer than two distinct x"
    return float(dx @ (le - le.mean())) / sxx, ""


def agrees(fitted, predicted, tolerance):
    """Agreement of a fitted rate with a predicted exponent: fitted >= predicted - tolerance."""
    return math.isfinite(fitted) and fitted >= predicted - tolerance


def monotone_until_floor(x, e, floor_ratio):
    """The monotone check on one series: (passed, detail).

    x must decrease along the levels and e decrease, e_k <= e_{k-1} (1 + MONOTONE_RTOL), until a
    floor. The floor starts at the first level k with e_k > floor_ratio * e_{k-1}; its value is
    F = e_{k-1}, and from level k on every e must lie in [F/2, 2F].
    """
    for k in range(1, len(x)):
        if not x[k] < x[k - 1]:  # also catches nan
            return False, f"x does not decrease along the levels (x_{k - 1} = {x[k - 1]!r}, x_{k} = {x[k]!r})"
    for k, v in enumerate(e):
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0:
            return False, f"e_{k} = {v!r} is not a finite number >= 0"
    for k in range(1, len(e)):
        if e[k] > floor_ratio * e[k - 1]:
            floor = e[k - 1]
            lo, hi = FLOOR_BAND[0] * floor, FLOOR_BAND[1] * floor
            for j in range(k, len(e)):
                if not lo <= e[j] <= hi:
                    return False, (f"floor from level {k} at {floor:.4g}, but e_{j} = {e[j]:.4g} "
                                   f"is outside [{lo:.4g}, {hi:.4g}]")
            return True, f"decreases until level {k - 1}, then stays at the floor {floor:.4g}"
        if e[k] > e[k - 1] * (1 + MONOTONE_RTOL):
            return False, f"e increases before the floor: e_{k - 1} = {e[k - 1]:.4g}, e_{k} = {e[k]:.4g}"
    return True, f"decreases over all {len(e)} levels, no floor"

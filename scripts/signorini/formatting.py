"""Numbers as text for the tables and sentences of the reports."""
import math

import numpy as np


def finite(v):
    """A finite int or float (booleans are not numbers here)."""
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def sci(v, digits=2):
    """Compact scientific notation: 8.1e-3; nan -> 'nan'."""
    if not finite(v):
        return "nan"
    s = f"{v:.{digits - 1}e}"
    mant, exp = s.split("e")
    return f"{mant}e{int(exp)}"


def short(v):
    """Shortest scientific form that reads back as v (targets: 1e-2, 3e-3, 2.5e-2)."""
    for d in range(1, 8):
        s = sci(v, d)
        if float(s) == v:
            return s
    return repr(v)


def fmt_time(v):
    """Seconds: 3 significant digits, whole seconds from 100 s on; nan -> 'nan'."""
    return "nan" if not finite(v) else (f"{v:.3g}" if v < 100 else f"{v:.0f}")


def fmt_mem(v):
    """Megabytes, whole; 'n/a' when unknown."""
    return "n/a" if not finite(v) else f"{v:.0f}"


def fmt_val(v):
    """A float in compact scientific notation (3 digits), None empty, anything else as text."""
    if isinstance(v, float):
        return sci(v, 3)
    return "" if v is None else str(v)


def fmt_sig(v, digits=3):
    """`digits` significant digits; integers whole, strings as they are, None, '' and nan -> '-'."""
    if v is None or v == "":
        return "-"
    if isinstance(v, str):
        return v
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if np.isnan(v):
        return "-"
    return f"{v:.{digits}g}"


def format_rate(rate, note):
    """A rate with 3 decimals, or 'nan (why)'."""
    return f"{rate:.3f}" if not note else f"nan ({note})"


def format_value(v):
    """A norm or abscissa value for the Markdown tables."""
    return f"{v:.4e}" if isinstance(v, float) else str(v)

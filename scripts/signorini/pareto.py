"""Cost-error analysis of a set of runs (dict rows with "ok", "cost", the error norms and "index",
the plan order): usable runs, dominance, Pareto fronts and recommendations."""
from .formatting import finite

ERROR_RTOL = 1e-6  # default error_rtol: errors this close count as equal in the Pareto fronts


def usable(row, norm):
    """A converged run with a finite cost and a finite value of `norm`."""
    return bool(row.get("ok")) and finite(row.get("cost")) and finite(row.get(norm))


def same_error(ea, eb, rtol):
    """Errors equal within the relative tolerance rtol."""
    return abs(ea - eb) <= rtol * max(abs(ea), abs(eb))


def dominates(a, b, norm, rtol=ERROR_RTOL):
    """a is no slower and no less accurate than b (errors within rtol count as equal), and
    strictly better in one of the two."""
    ca, cb, ea, eb = a["cost"], b["cost"], a[norm], b[norm]
    close = same_error(ea, eb, rtol)
    return ca <= cb and (ea <= eb or close) and (ca < cb or (ea < eb and not close))


def pareto_front(rows, norm, rtol=ERROR_RTOL):
    """The usable rows that no usable row dominates, sorted by cost, error, plan order."""
    cand = [r for r in rows if usable(r, norm)]
    front = [r for r in cand if not any(dominates(o, r, norm, rtol) for o in cand if o is not r)]
    return sorted(front, key=lambda r: (r["cost"], r[norm], r.get("index", 0)))


def recommend(rows, norm, target):
    """The cheapest usable row with error <= target (ties: smaller error, then plan order)."""
    ok = [r for r in rows if usable(r, norm) and r[norm] <= target]
    if not ok:
        return None
    return min(ok, key=lambda r: (r["cost"], r[norm], r.get("index", 0)))

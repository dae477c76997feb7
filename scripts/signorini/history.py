"""A load path's history (/steps of an output written with -load_steps or -load_path): its columns, and the
indentation depth, the obstacle's translation along the direction it moves in, with the obstacle's force along it."""
import numpy as np

from .runs import read_steps


def history(path):
    """{column: 1-D array} of /steps, plus, where the obstacle moves: depth (its translation along the unit direction
    of the largest translation on the path) and force_along (the obstacle's force on the body along that direction,
    positive when it presses). Raises ValueError for a file without /steps."""
    steps, _ = read_steps(path)
    if not steps:
        raise ValueError(f"{path}: no /steps (not a load path's output: run with -load_steps or -load_path)")
    axes = [c for c in "xyz" if f"obstacle_translate_{c}" in steps]
    T = np.column_stack([steps[f"obstacle_translate_{c}"] for c in axes])
    F = np.column_stack([steps[f"contact_force_{c}"] for c in axes])
    norms = np.linalg.norm(T, axis=1)
    if norms.max() > 0.0:
        direction = T[np.argmax(norms)] / norms.max()
        steps["depth"] = T @ direction
        steps["force_along"] = F @ direction
    return steps

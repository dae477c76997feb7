"""Where things are: the scripts directory, the repository root (the working directory of every
run) and the solver binary."""
import os

SCRIPTS = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ROOT = os.path.dirname(SCRIPTS)
BIN = "bin/signorini"  # relative to ROOT, the working directory of every run


def display_path(path):
    """`path` relative to ROOT when inside it (as the runs see it), else absolute."""
    path = os.path.abspath(path)
    rel = os.path.relpath(path, ROOT)
    return path if rel.startswith("..") else rel

#!/usr/bin/python3
"""Counts the fields of the C structures of the sources: what each object holds, as the restructuring of issue 30
measured it (the run's state, the SNES callbacks' context, the Contact).

  struct_fields.py [--rev REV] [NAME ...]

For each structure NAME (a typedef'd struct, or struct _p_X / _n_X) of include/*.h and src/*/*.h: its members, and its
leaves, the members with every nested structure of the same headers expanded (a pointer counts as one leaf, whatever
it points to). --rev reads the headers of a git revision instead of the working tree. Without names: the run's state
(AppCtx, Problem), the callbacks' context (_n_SolverCtx) and the Contact (_p_Contact).
"""
import argparse
import glob
import os
import re
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from signorini.paths import ROOT  # noqa: E402

DEFAULT = ["AppCtx", "Problem", "RunOptions", "_n_SolverCtx", "_p_Contact"]


def headers(rev):
    if rev is None:
        paths = sorted(glob.glob(os.path.join(ROOT, "include", "*.h")) + glob.glob(os.path.join(ROOT, "src", "*", "*.h")))
        return "\n".join(open(p).read() for p in paths)
    names = subprocess.run(["git", "ls-tree", "-r", "--name-only", rev], cwd=ROOT, capture_output=True, text=True, check=True).stdout.split()
    paths = [n for n in names if n.endswith(".h") and (n.startswith("include/") or re.match(r"src/[^/]+/[^/]+\.h$", n))]
    return "\n".join(subprocess.run(["git", "show", f"{rev}:{p}"], cwd=ROOT, capture_output=True, text=True, check=True).stdout for p in paths)


def structures(text):
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    found = {}
    for m in re.finditer(r"typedef\s+struct\s*\w*\s*\{(.*?)\}\s*(\w+)\s*;", text, flags=re.S):
        found[m.group(2)] = m.group(1)
    for m in re.finditer(r"^struct\s+(\w+)\s*\{(.*?)\}\s*;", text, flags=re.S | re.M):
        found[m.group(1)] = m.group(2)
    return found


def members(body):
    """(type, declarator) of each member; a function pointer is one member of type 'function'."""
    out = []
    for stmt in body.split(";"):
        stmt = " ".join(stmt.split())
        if not stmt:
            continue
        if "(*" in stmt:
            out.append(("function", stmt))
            continue
        m = re.match(r"(?:const\s+)?(?:struct\s+)?(\w+)\s*(.*)", stmt)
        if m:
            out.extend((m.group(1), d.strip()) for d in m.group(2).split(",") if d.strip())
    return out


def leaves(name, found):
    total = 0
    for typ, decl in members(found[name]):
        total += 1 if decl.startswith("*") or typ not in found else leaves(typ, found)
    return total


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("names", nargs="*", default=DEFAULT)
    ap.add_argument("--rev", help="a git revision (default: the working tree)")
    args = ap.parse_args(argv)
    found = structures(headers(args.rev))
    for name in args.names:
        if name in found:
            print(f"{name}: {len(members(found[name]))} members, {leaves(name, found)} leaves")
        else:
            print(f"{name}: none")
    return 0


if __name__ == "__main__":
    sys.exit(main())

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


def closing(text, i):
    """The index of the brace that closes the one at text[i]."""
    depth = 0
    for j in range(i, len(text)):
        depth += {"{": 1, "}": -1}.get(text[j], 0)
        if depth == 0:
            return j
    raise ValueError("unbalanced braces")


def structures(text):
    """{name: body} of the typedef'd structs and of struct X { ... }; at the top level, their braces matched (a nested
    struct { ... } member; is part of its body)."""
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    text = re.sub(r"//[^\n]*", "", text)
    found = {}
    for m in re.finditer(r"^(typedef\s+)?struct\s*(\w*)\s*\{", text, flags=re.M):
        end = closing(text, m.end() - 1)
        body = text[m.end():end]
        tail = re.match(r"\s*(\w*)\s*;", text[end + 1:])
        name = tail.group(1) if m.group(1) and tail and tail.group(1) else m.group(2)
        if name:
            found[name] = body
    return found


def statements(body):
    """The members' declarations of a struct body, split at the semicolons outside nested braces."""
    out, depth, start = [], 0, 0
    for i, ch in enumerate(body):
        depth += {"{": 1, "}": -1}.get(ch, 0)
        if ch == ";" and depth == 0:
            out.append(body[start:i])
            start = i + 1
    return out


def members(body):
    """(type, declarator) of each member; a function pointer is one member of type 'function', a nested anonymous
    struct one member whose type is its body in braces."""
    out = []
    for stmt in statements(body):
        stmt = " ".join(stmt.split())
        if not stmt:
            continue
        if "{" in stmt:
            inner = stmt[stmt.index("{") + 1:stmt.rindex("}")]
            out.extend(("{" + inner + "}", d.strip()) for d in stmt[stmt.rindex("}") + 1:].split(",") if d.strip())
            continue
        if "(*" in stmt:
            out.append(("function", stmt))
            continue
        m = re.match(r"(?:const\s+)?(?:struct\s+)?(\w+)\s*(.*)", stmt)
        if m:
            out.extend((m.group(1), d.strip()) for d in m.group(2).split(",") if d.strip())
    return out


def leaves_of(body, found):
    total = 0
    for typ, decl in members(body):
        if typ.startswith("{"):
            total += leaves_of(typ[1:-1], found)
        else:
            total += 1 if decl.startswith("*") or typ not in found else leaves_of(found[typ], found)
    return total


def leaves(name, found):
    return leaves_of(found[name], found)


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

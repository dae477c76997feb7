#!/usr/bin/python3
"""Writes a Gmsh mesh of a body that touches the plane x_d = 0 at the origin, finer toward that point
(scripts/signorini/geometry.py), for -dm_plex_filename.

  make_mesh.py half-disk      -o FILE.msh [--radius R] [--h-far H] [--h-near h] [--width W]   (2D, triangles)
  make_mesh.py quarter-disk   -o FILE.msh [--radius R] [--h-far H] [--h-near h] [--width W]   (2D, triangles)
  make_mesh.py quarter-sphere -o FILE.msh [--radius R] [--h-far H] [--h-near h] [--width W]   (3D, tetrahedra)
  make_mesh.py block          -o FILE.msh [--radius R] ...   (2D: [0,R] x [-R,0], indented at the origin from above)
  make_mesh.py quarter-block  -o FILE.msh [--radius R] ...   (3D: [0,R]^2 x [-R,0])

With --model FILE.geo the geometry is written too (FILE.geo and FILE.brep): the model the solver remeshes with
-adapt_model when it refines a curved body or a 3D mesh (docs/estimate.md).
The mesh size is h_near at the origin and h_near + G r up to the distance --near from it (--grade G, default 0: the
size is h_near there), then grows linearly to h_far over the distance W (default R/2). A grade keeps the cells across
a contact zone that grows, as along a load path, about as many at every size of it (docs/hertz.md).
Physical groups ("Face Sets" values, and names): half-disk contact 1, top 3; quarter-disk contact 1, top 3,
symmetry_x 4; quarter-sphere contact 1, top 2, symmetry_y 3, symmetry_x 6; block contact 1, bottom 2, symmetry_x 4,
side 5; quarter-block contact 1, bottom 2, symmetry_y 3, side 5, symmetry_x 6; the body 10. The built-in scenes
(Gamma_C = 1, clamped top) run on the disk and sphere meshes as they are; the scene general takes the names.
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from signorini.geometry import SHAPES  # noqa: E402

DEFAULTS = {"half-disk": (0.1, 0.02), "quarter-disk": (0.1, 0.02), "quarter-sphere": (0.2, 0.05), "block": (0.1, 0.02), "quarter-block": (0.2, 0.05)}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("shape", choices=sorted(SHAPES))
    parser.add_argument("-o", "--output", required=True, help="the .msh file to write")
    parser.add_argument("--radius", type=float, default=1.0)
    parser.add_argument("--h-far", type=float, help="mesh size far from the contact point")
    parser.add_argument("--h-near", type=float, help="mesh size at the contact point")
    parser.add_argument("--width", type=float, help="distance over which the size grows from h-near to h-far (default radius/2)")
    parser.add_argument("--near", type=float, default=0.0, help="distance from the origin up to which the size is h-near + grade r (default 0)")
    parser.add_argument("--grade", type=float, default=0.0, help="growth of the size with the distance r inside --near (default 0)")
    parser.add_argument("--model", help="also write the geometry as a Gmsh model (a .geo and its .brep), for -adapt_model")
    args = parser.parse_args(argv)
    h_far = args.h_far if args.h_far is not None else DEFAULTS[args.shape][0] * args.radius
    h_near = args.h_near if args.h_near is not None else DEFAULTS[args.shape][1] * args.radius
    for path in (args.output, args.model):  # as the solver makes its output's directory: output/x.msh on a fresh clone
        if path and os.path.dirname(path):
            os.makedirs(os.path.dirname(path), exist_ok=True)
    try:
        SHAPES[args.shape](args.output, radius=args.radius, h_far=h_far, h_near=h_near, width=args.width, near=args.near, grade=args.grade,
                            model=args.model)
    except ValueError as exc:
        print(f"make_mesh.py: {exc}", file=sys.stderr)
        return 2
    print(f"written {args.output}" + (f", {args.model}" if args.model else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())

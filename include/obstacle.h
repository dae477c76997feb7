/* The rigid obstacle's geometry, shared by the pointwise kernels (which read it from constants[CONST_OBSTACLE]) and
   the node-by-node code: the gap g and the unit normal n at an undeformed position x (small deformation), so that
   the penetration of a displacement u is u . n - g. No PETSc calls: the kernels call it. */
#pragma once
#include "signorini.h"

/* The coordinates of r = x - P about an obstacle's axis a (p[OBSTACLE_DIRECTION]): z = r . a along it, rho the distance
   from it, and e the unit vector of r - z a (zero on the axis). */
static inline void ObstacleAxialFrame(PetscInt dim, const PetscScalar p[], const PetscReal r[], PetscReal *z, PetscReal *rho, PetscReal e[])
{
  *z   = 0.0;
  *rho = 0.0;
  for (PetscInt c = 0; c < dim; ++c) *z += r[c] * PetscRealPart(p[OBSTACLE_DIRECTION + c]);
  for (PetscInt c = 0; c < dim; ++c) e[c] = r[c] - *z * PetscRealPart(p[OBSTACLE_DIRECTION + c]);
  for (PetscInt c = 0; c < dim; ++c) *rho += e[c] * e[c];
  *rho = PetscSqrtReal(*rho);
  for (PetscInt c = 0; c < dim; ++c) e[c] = *rho > 0.0 ? e[c] / *rho : 0.0;
}

/* p: the packed parameters (OBSTACLE_* order). n points from the body into the obstacle; g is the distance from x
   to the obstacle's surface along n (negative when x starts inside the obstacle).
   plane:    n = the plane's normal, g = (point - x) . n;
   sphere:   the body stays outside the ball, r = x - center, n = -r/|r|, g = |r| - radius;
   cylinder: the same with r perpendicular to the axis (in 2D a disk, like the sphere);
   cone:     apex P, unit axis a from the apex into the cone, half-angle alpha (in 2D a wedge). With z = (x - P) . a and
             rho e = (x - P) - z a (e a unit vector away from the axis), the cone's surface in the plane of a and e is
             the ray t (sin alpha e + cos alpha a), t >= 0. Its point closest to x is at t = rho sin alpha + z cos alpha:
             for t > 0 the foot of the perpendicular, g = rho cos alpha - z sin alpha (the signed distance to the ray's
             line, negative inside the cone) with n = -cos alpha e + sin alpha a, the surface's normal into the cone;
             for t <= 0 the apex itself, g = |x - P| and n = (P - x)/|x - P|;
   punch:    a cylinder of axis a whose flat end, centered at P, has radius A (in 2D a half-width) and a fillet of radius
             r >= 0 round its edge: in the plane of a and e as for the cone, the end z = 0 for rho <= A, the fillet the
             quarter circle of center C = (A, r), the side rho = A + r. Below the end (rho <= A) g = -z and n = a; beside
             it, below the fillet's center (rho > A, z < r), the closest point is on the fillet (the edge itself for
             r = 0), g = |v| - r and n = -v/|v| with v = (rho - A, z - r); above it, the side, g = rho - A - r, n = -e. */
static inline void ObstacleGapNormal(PetscInt dim, const PetscScalar p[], const PetscReal x[], PetscReal n[], PetscReal *g)
{
  const ObstacleType type = (ObstacleType)(PetscInt)PetscRealPart(p[OBSTACLE_TYPE]);
  PetscReal          r[3] = {0.0, 0.0, 0.0}, len = 0.0;

  if (type == OBSTACLE_PLANE) {
    *g = 0.0;
    for (PetscInt c = 0; c < dim; ++c) {
      n[c] = PetscRealPart(p[OBSTACLE_DIRECTION + c]);
      *g += (PetscRealPart(p[OBSTACLE_POINT + c]) - x[c]) * n[c];
    }
    return;
  }
  for (PetscInt c = 0; c < dim; ++c) r[c] = x[c] - PetscRealPart(p[OBSTACLE_POINT + c]);
  if (type == OBSTACLE_CONE) {
    const PetscReal sa = PetscRealPart(p[OBSTACLE_CONE_SIN]), ca = PetscRealPart(p[OBSTACLE_CONE_COS]);
    PetscReal       z, rho, e[3];

    ObstacleAxialFrame(dim, p, r, &z, &rho, e);
    if (rho * sa + z * ca > 0.0) { /* the foot of the perpendicular on the surface (on the axis: the axis) */
      for (PetscInt c = 0; c < dim; ++c)
        n[c] = rho > 0.0 ? -ca * e[c] + sa * PetscRealPart(p[OBSTACLE_DIRECTION + c]) : PetscRealPart(p[OBSTACLE_DIRECTION + c]);
      *g = rho * ca - z * sa;
    } else { /* the apex */
      len = PetscSqrtReal(rho * rho + z * z);
      for (PetscInt c = 0; c < dim; ++c) n[c] = len > 0.0 ? -r[c] / len : 0.0;
      *g = len;
    }
    return;
  }
  if (type == OBSTACLE_PUNCH) {
    const PetscReal A = PetscRealPart(p[OBSTACLE_RADIUS]), rf = PetscRealPart(p[OBSTACLE_EDGE_RADIUS]);
    PetscReal       z, rho, e[3];

    ObstacleAxialFrame(dim, p, r, &z, &rho, e);
    if (rho <= A) { /* below the flat end */
      for (PetscInt c = 0; c < dim; ++c) n[c] = PetscRealPart(p[OBSTACLE_DIRECTION + c]);
      *g = -z;
    } else if (z < rf) { /* beside it, below the fillet's center: the fillet, or for r = 0 the edge */
      const PetscReal vr = rho - A, vz = z - rf, vl = PetscSqrtReal(vr * vr + vz * vz);

      for (PetscInt c = 0; c < dim; ++c) n[c] = vl > 0.0 ? -(vr * e[c] + vz * PetscRealPart(p[OBSTACLE_DIRECTION + c])) / vl : 0.0;
      *g = vl - rf;
    } else { /* the side */
      for (PetscInt c = 0; c < dim; ++c) n[c] = -e[c];
      *g = rho - A - rf;
    }
    return;
  }
  if (type == OBSTACLE_CYLINDER && dim == 3) {
    PetscReal ra = 0.0;

    for (PetscInt c = 0; c < 3; ++c) ra += r[c] * PetscRealPart(p[OBSTACLE_DIRECTION + c]);
    for (PetscInt c = 0; c < 3; ++c) r[c] -= ra * PetscRealPart(p[OBSTACLE_DIRECTION + c]);
  }
  for (PetscInt c = 0; c < dim; ++c) len += r[c] * r[c];
  len = PetscSqrtReal(len);
  for (PetscInt c = 0; c < dim; ++c) n[c] = len > 0.0 ? -r[c] / len : 0.0;
  *g = len - PetscRealPart(p[OBSTACLE_RADIUS]);
}

/* The parameters of an obstacle in the packed order, its translation added to its point. */
static inline void ObstaclePack(const Obstacle *obs, PetscScalar p[])
{
  p[OBSTACLE_TYPE] = (PetscReal)obs->type;
  for (PetscInt c = 0; c < 3; ++c) {
    p[OBSTACLE_POINT + c]     = obs->point[c] + obs->translate[c];
    p[OBSTACLE_DIRECTION + c] = obs->direction[c];
  }
  p[OBSTACLE_RADIUS] = obs->radius;
  /* a cone's half-angle as its sine and cosine, so that the kernels take no trigonometric function */
  p[OBSTACLE_CONE_SIN]    = obs->type == OBSTACLE_CONE ? PetscSinReal(obs->half_angle * PETSC_PI / 180.0) : 0.0;
  p[OBSTACLE_CONE_COS]    = obs->type == OBSTACLE_CONE ? PetscCosReal(obs->half_angle * PETSC_PI / 180.0) : 1.0;
  p[OBSTACLE_EDGE_RADIUS] = obs->edge_radius;
}

/* The penetration u . n - g at x for the packed obstacle p; n is returned too. */
static inline PetscReal ObstaclePenetration(PetscInt dim, const PetscScalar p[], const PetscReal x[], const PetscScalar u[], PetscReal n[])
{
  PetscReal g, d = 0.0;

  ObstacleGapNormal(dim, p, x, n, &g);
  for (PetscInt c = 0; c < dim; ++c) d += PetscRealPart(u[c]) * n[c];
  return d - g;
}

/* The obstacle's normal (and gap) at x, from the unpacked obstacle. */
static inline void ObstacleGapNormalAt(const Obstacle *obs, PetscInt dim, const PetscReal x[], PetscReal n[], PetscReal *g)
{
  PetscScalar p[OBSTACLE_NUM_PARAMS];

  ObstaclePack(obs, p);
  ObstacleGapNormal(dim, p, x, n, g);
}

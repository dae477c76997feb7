/* Closures and stars without PETSc 3.18's cell-type lookups. DMPlexGetTransitiveClosure() asks the "celltype" label for
   the type of every point it meets, and PETSc keeps that label's strata as hash sets during most of the set-up: a
   hash-set query for every point of every closure. In a mesh whose
   points of each depth all have one type (simplices, or tensor cells, interpolated), the type follows from the depth,
   and this is PETSc's breadth-first walk with the same arrangements and orientations, so it lists the same points in
   the same order. Any other mesh takes DMPlexGetTransitiveClosure() itself.
   One of PETSc 3.18's mirrors (docs/decisions.md, "PETSc 3.18's mirrors"). */
#include "mesh.h"

/* One cell type per depth, each of that depth's dimension, and an interpolated mesh (depth = dimension). */
static PetscErrorCode MeshClosureTypesByDepth(DM dm, MeshClosure *mc)
{
  DMLabel  ct_label;
  PetscInt dim, local = 1;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMPlexGetDepth(dm, &mc->depth));
  PetscCall(DMPlexGetCellTypeLabel(dm, &ct_label));
  if (mc->depth != dim || dim > 3) local = 0;
  for (PetscInt d = 0; local && d <= mc->depth; ++d) {
    PetscInt pStart, pEnd, n;

    PetscCall(DMPlexGetDepthStratum(dm, d, &pStart, &pEnd));
    mc->start[d] = pStart;
    mc->end[d]   = pEnd;
    if (pEnd == pStart) continue; /* an empty rank: no type to fix */
    PetscCall(DMPlexGetCellType(dm, pStart, &mc->type[d]));
    PetscCall(DMLabelGetStratumSize(ct_label, (PetscInt)mc->type[d], &n));
    if (n != pEnd - pStart || DMPolytopeTypeGetDim(mc->type[d]) != d) local = 0;
    switch (mc->type[d]) {
      case DM_POLYTOPE_POINT:
      case DM_POLYTOPE_SEGMENT:
      case DM_POLYTOPE_TRIANGLE:
      case DM_POLYTOPE_QUADRILATERAL:
      case DM_POLYTOPE_TETRAHEDRON:
      case DM_POLYTOPE_HEXAHEDRON:
        break;
      default:
        local = 0;
    }
  }
  mc->by_depth = local ? PETSC_TRUE : PETSC_FALSE; /* per rank: both paths list the same points */
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode MeshClosureCreate(DM dm, MeshClosure *mc)
{
  PetscInt   max_cone, max_support, pStart, pEnd;
  PetscInt64 series[2] = {1, 1}, term[2] = {1, 1};

  PetscFunctionBeginUser;
  PetscCall(PetscMemzero(mc, sizeof(*mc)));
  mc->dm = dm;
  PetscCall(DMGetDimension(dm, &mc->dim));
  PetscCall(DMPlexGetDepthStratum(dm, 0, &mc->vstart, &mc->vend));
  PetscCall(MeshClosureTypesByDepth(dm, mc));
  PetscCall(DMPlexGetMaxSizes(dm, &max_cone, &max_support));
  PetscCall(DMPlexGetChart(dm, &pStart, &pEnd));
  for (PetscInt d = 1; d <= mc->depth; ++d) { /* PETSc's bound, 1 + m + ... + m^depth, in 64 bits (m^4 overflows 32) */
    term[0] = PetscMin(term[0] * PetscMax(max_cone, 1), (PetscInt64)pEnd);
    term[1] = PetscMin(term[1] * PetscMax(max_support, 1), (PetscInt64)pEnd);
    series[0] += term[0];
    series[1] += term[1];
  }
  mc->max_points = (PetscInt)PetscMin(PetscMax(series[0], series[1]), (PetscInt64)PetscMax(pEnd - pStart, 1)); /* at most every point */
  PetscCall(PetscMalloc2(2 * mc->max_points, &mc->points, 4 * mc->max_points, &mc->fifo)); /* MeshClosureVertices(): two lists of pairs */
  PetscCall(DMPlexGetConeSection(dm, &mc->cone_section));
  PetscCall(DMPlexGetCones(dm, &mc->cones));
  PetscCall(DMPlexGetConeOrientations(dm, &mc->cone_ornts));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode MeshClosureDestroy(MeshClosure *mc)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFree2(mc->points, mc->fifo));
  PetscCall(PetscMemzero(mc, sizeof(*mc)));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscInt MeshClosureDepthOf(const MeshClosure *mc, PetscInt p)
{
  for (PetscInt d = 0; d <= mc->depth; ++d)
    if (p >= mc->start[d] && p < mc->end[d]) return d;
  return -1;
}

/* The closure (use_cone) or star of p as DMPlexGetTransitiveClosure() gives it: *n points, (point, orientation) pairs
   in *points, which stays valid until the next call on mc. */
PetscErrorCode MeshClosureGet(MeshClosure *mc, PetscInt p, PetscBool use_cone, PetscInt *n, const PetscInt **points)
{
  DM        dm      = mc->dm;
  PetscInt *closure = mc->points, *fifo = mc->fifo, size = 0, head = 0, tail = 0, depth;

  PetscFunctionBeginUser;
  if (!mc->by_depth) {
    PetscInt *cl = NULL;

    PetscCall(DMPlexGetTransitiveClosure(dm, p, use_cone, n, &cl));
    PetscCheck(*n <= mc->max_points, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Closure of %" PetscInt_FMT " has %" PetscInt_FMT " points", p, *n);
    PetscCall(PetscArraycpy(closure, cl, 2 * *n));
    PetscCall(DMPlexRestoreTransitiveClosure(dm, p, use_cone, n, &cl));
    *points = closure;
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  depth = MeshClosureDepthOf(mc, p);
  PetscCheck(depth >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "Point %" PetscInt_FMT " is in no depth stratum", p);
  closure[size++] = p;
  closure[size++] = 0;
  fifo[tail++]    = p;
  fifo[tail++]    = 0;
  fifo[tail++]    = depth;
  while (tail > head) {
    const PetscInt  q = fifo[head++], o = fifo[head++], qd = fifo[head++], cd = use_cone ? qd - 1 : qd + 1;
    const PetscInt *qarr, *tmp, *tmp_o = NULL;
    PetscInt        ntmp;

    if (cd < 0 || cd > mc->depth) continue;
    qarr = DMPolytopeTypeGetArrangment(mc->type[qd], o);
    if (use_cone) { /* DMPlexGetCone() and DMPlexGetConeOrientation() without their checks */
      PetscInt off;

      PetscCall(PetscSectionGetDof(mc->cone_section, q, &ntmp));
      PetscCall(PetscSectionGetOffset(mc->cone_section, q, &off));
      tmp   = &mc->cones[off];
      tmp_o = &mc->cone_ornts[off];
    } else {
      PetscCall(DMPlexGetSupportSize(dm, q, &ntmp));
      PetscCall(DMPlexGetSupport(dm, q, &tmp));
    }
    for (PetscInt t = 0; t < ntmp; ++t) {
      const PetscInt ip = use_cone && qarr ? qarr[t * 2] : t, io = use_cone && qarr ? qarr[t * 2 + 1] : 0, cp = tmp[ip];
      const PetscInt co = tmp_o ? DMPolytopeTypeComposeOrientation(mc->type[cd], io, tmp_o[ip]) : 0;
      PetscInt       c;

      for (c = 0; c < size; c += 2)
        if (closure[c] == cp) break;
      if (c < size) continue;
      PetscCheck(size / 2 < mc->max_points, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Closure of %" PetscInt_FMT " exceeds %" PetscInt_FMT " points", p,
                 mc->max_points);
      closure[size++] = cp;
      closure[size++] = co;
      fifo[tail++]    = cp;
      fifo[tail++]    = co;
      fifo[tail++]    = cd;
    }
  }
  *n      = size / 2;
  *points = closure;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The vertices of the closure of p, in the closure's order (MeshClosureGet() with the other points dropped), level by
   level: the closure is a breadth-first walk down the depths, so its points of one depth follow those of the depth
   above, each level in the order its points are met; no point of one level is in another. verts holds max. */
PetscErrorCode MeshClosureVertices(MeshClosure *mc, PetscInt p, PetscInt max, PetscInt *nv, PetscInt verts[])
{
  PetscInt *cur = mc->fifo, *next, ncur = 1, depth;

  PetscFunctionBeginUser;
  if (!mc->by_depth) {
    const PetscInt *cl;
    PetscInt        ncl;

    PetscCall(MeshClosureGet(mc, p, PETSC_TRUE, &ncl, &cl));
    *nv = 0;
    for (PetscInt k = 0; k < ncl; ++k)
      if (cl[2 * k] >= mc->vstart && cl[2 * k] < mc->vend) {
        PetscCheck(*nv < max, PETSC_COMM_SELF, PETSC_ERR_ARG_SIZ, "Point %" PetscInt_FMT " has more than %" PetscInt_FMT " vertices", p, max);
        verts[(*nv)++] = cl[2 * k];
      }
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  depth = MeshClosureDepthOf(mc, p);
  PetscCheck(depth >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "Point %" PetscInt_FMT " is in no depth stratum", p);
  next   = mc->fifo + 2 * mc->max_points; /* two lists of (point, orientation) in the walk's scratch space */
  cur[0] = p;
  cur[1] = 0;
  for (PetscInt qd = depth; qd > 0; --qd) {
    PetscInt nnext = 0, *swap;

    for (PetscInt i = 0; i < ncur; ++i) {
      const PetscInt  q = cur[2 * i], *qarr = DMPolytopeTypeGetArrangment(mc->type[qd], cur[2 * i + 1]);
      const PetscInt *tmp, *tmp_o;
      PetscInt        ntmp, off;

      PetscCall(PetscSectionGetDof(mc->cone_section, q, &ntmp));
      PetscCall(PetscSectionGetOffset(mc->cone_section, q, &off));
      tmp   = &mc->cones[off];
      tmp_o = &mc->cone_ornts[off];
      for (PetscInt t = 0; t < ntmp; ++t) {
        const PetscInt ip = qarr ? qarr[t * 2] : t, io = qarr ? qarr[t * 2 + 1] : 0, cp = tmp[ip];
        PetscInt       c;

        for (c = 0; c < nnext; ++c)
          if (next[2 * c] == cp) break;
        if (c < nnext) continue;
        PetscCheck(nnext < mc->max_points, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Closure of %" PetscInt_FMT " exceeds %" PetscInt_FMT " points", p,
                   mc->max_points);
        next[2 * nnext]     = cp;
        next[2 * nnext + 1] = DMPolytopeTypeComposeOrientation(mc->type[qd - 1], io, tmp_o[ip]);
        ++nnext;
      }
    }
    swap = cur;
    cur  = next;
    next = swap;
    ncur = nnext;
  }
  PetscCheck(ncur <= max, PETSC_COMM_SELF, PETSC_ERR_ARG_SIZ, "Point %" PetscInt_FMT " has %" PetscInt_FMT " > %" PetscInt_FMT " vertices", p, ncur,
             max);
  for (PetscInt i = 0; i < ncur; ++i) verts[i] = cur[2 * i];
  *nv = ncur;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Compares MeshClosureGet() with DMPlexGetTransitiveClosure() on every point, closure and star: the number of points
   that differ (0 on any mesh), and whether the walk by depth served (else both are PETSc's). */
PetscErrorCode MeshClosureCheck(DM dm, PetscInt *differences, PetscBool *by_depth)
{
  MeshClosure mc;
  PetscInt    pStart, pEnd;

  PetscFunctionBeginUser;
  *differences = 0;
  PetscCall(MeshClosureCreate(dm, &mc));
  *by_depth = mc.by_depth;
  PetscCall(DMPlexGetChart(dm, &pStart, &pEnd));
  for (PetscInt p = pStart; p < pEnd; ++p)
    for (PetscInt k = 0; k < 2; ++k) {
      const PetscBool use_cone = k ? PETSC_FALSE : PETSC_TRUE;
      const PetscInt *mine;
      PetscInt       *ref = NULL, n_mine, n_ref;

      PetscCall(MeshClosureGet(&mc, p, use_cone, &n_mine, &mine));
      PetscCall(DMPlexGetTransitiveClosure(dm, p, use_cone, &n_ref, &ref));
      if (n_mine != n_ref)
        ++*differences;
      else
        for (PetscInt i = 0; i < 2 * n_ref; ++i)
          if (mine[i] != ref[i]) {
            ++*differences;
            break;
          }
      if (use_cone) { /* and the closure's vertices */
        PetscInt nv, nref_v = 0, *verts, *ref_v;

        PetscCall(PetscMalloc2(mc.max_points, &verts, n_ref, &ref_v));
        PetscCall(MeshClosureVertices(&mc, p, mc.max_points, &nv, verts));
        for (PetscInt i = 0; i < n_ref; ++i)
          if (ref[2 * i] >= mc.vstart && ref[2 * i] < mc.vend) ref_v[nref_v++] = ref[2 * i];
        if (nv != nref_v)
          ++*differences;
        else
          for (PetscInt i = 0; i < nv; ++i)
            if (verts[i] != ref_v[i]) {
              ++*differences;
              break;
            }
        PetscCall(PetscFree2(verts, ref_v));
      }
      PetscCall(DMPlexRestoreTransitiveClosure(dm, p, use_cone, &n_ref, &ref));
    }
  PetscCall(MeshClosureDestroy(&mc));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Error bars of the quantities users read (-bars): the contact force, the largest pressure, the contact zone's size, the
   largest penetration, the energy and the supports' reactions.

   The mesh's part. The grid sequence solves the problem on nested meshes h1 = h (the final one), h2 = 2h, h3 = 4h, all
   at the final mesh's eps and to the final tolerance (src/drivers/grid_sequence.c), so that a quantity Q differs between
   them by its discretization error alone. If Q(h) = Q* + C h^p, the differences e21 = Q2 - Q1 and e32 = Q3 - Q2 have
   the ratio e21 / e32 = 2^-p, which gives the observed order p, and Richardson's extrapolation the error of Q1,
   e21 / (2^p - 1). Roache's grid convergence index (J. Fluids Eng. 116, 1994; ASME V&V 20-2009, section 2.4) multiplies
   it by the safety factor 1.25 of a three-mesh study:
     bar_mesh = 1.25 |e21| / (2^p - 1).
   Where the three meshes are not in the asymptotic range the formula means nothing, and no bar is given, with the
   reason: the differences change sign (oscillatory convergence), or grow (divergence), or give an order outside
   [BARS_ORDER_MIN, BARS_ORDER_MAX] (a P1 quantity converges at an order between about 1/2, a pressure peak at a kink,
   and 2, a smooth functional; outside a wider range the ratio of two differences is noise).

   The penalty's part. A second solve at eps / R, R = BARS_EPS_RATIO, on the 2h level gives d = Q(eps) - Q(eps / R). If
   Q(eps) = Q(0) + C eps^r with the order r known from theory, Roache's two-level index (safety factor 3, the one for a
   study whose order is not observed) bounds the error of Q(eps / R) by 3 |d| / (R^r - 1), and that of Q(eps) by
     bar_eps = |d| (1 + 3 / (R^r - 1)).
   r = 1 for a functional of the displacement (the force, the reactions, the energy, the penetration, the largest
   pressure): with the active set fixed the penalty solution is affine in eps to first order. r = 1/2 for the zone's
   size: its free edge moves like eps^(1/k) where the gap opens like s^k (k = 3/2 for smooth bodies as in Hertz, 5/2 for
   the manufactured solution), and 1/2 covers k up to 2.8 or so.

   The zone's size is a free boundary, resolved to a cell: its edge on the mesh moves by whole faces as h or eps falls
   (src/physics/contact_zone.c), so its differences are a staircase, not a power. Each level's band b (the one-cell strip
   along the edge) is its resolution, the floor of the size's mesh part:
     bar_mesh = max(grid convergence index, b1); where the levels are outside the asymptotic range but differ by no
                more than their bands (|e21| <= b2, |e32| <= b3: the staircase), bar_mesh = max(|e21|, b1).
   The largest nodal pressure is resolved to its step to its neighbours (PostprocessPressureStep()) in the same way: where
   its levels are outside the asymptotic range but differ by no more than their steps, bar_mesh = max(|e21|, step1) (on
   levels remeshed from a Gmsh model, whose nodes do not nest, the nodal maximum's differences change sign within the
   step); in the asymptotic range its index is not floored.
   (The size's penalty part is not floored: the 2h level sees the widening at eps = h only in part, 1/2 to 2/3 of the final
   mesh's on the manufactured solution, which the factor 2.39 of r = 1/2 and the floor of the mesh part cover; a floor
   of a 2h cell would make the bar of a Hertz zone at eps = h/10 thirty times its error. docs/estimate.md.)
   The bar is the sum of the parts, bar_mesh + bar_eps. */
#include <petscsf.h>
#include "contact.h"
#include "estimate.h"
#include "physics.h"
#include "app.h"

#define BARS_SAFETY 1.25           /* Roache's safety factor of a three-mesh study with its observed order */
#define BARS_SAFETY_TWO_LEVELS 3.0 /*   and of a two-level one whose order comes from theory */
#define BARS_ORDER_MIN 0.3
#define BARS_ORDER_MAX 5.0
#define BARS_SAME                                                                                                         \
  1e-8                          /* differences below this fraction of the quantity's kind are none: the solves' tolerance \
                                   (an iterative solver leaves a force component that symmetry makes 0 at 1e-11 of the force) */
#define BARS_EPS_ORDER 1.0      /* the penalty's order in eps of a functional of the displacement */
#define BARS_EPS_ORDER_EDGE 0.5 /*   and of the zone's size */

/* -bars needs three nested meshes and one eps; refused before the solve otherwise. nlevels: the meshes the run solves
   below the final one (the coarser boxes and the grid sequence's levels). */
PetscErrorCode BarsCheck(MPI_Comm comm, PetscBool bars, PetscInt nlevels, Contact contact)
{
  const ContactOptions *copt;

  PetscFunctionBeginUser;
  if (!bars) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(ContactGetOptions(contact, &copt));
  PetscCheck(nlevels >= BARS_LEVELS - 1, comm, PETSC_ERR_USER_INPUT,
             "-bars needs the solutions on three nested meshes, and this run solves %" PetscInt_FMT
             ": give -contact_grid_sequence 2 (the mesh of the options and two uniform refinements of it), or on a box -contact_coarse_levels 2",
             nlevels + 1);
  PetscCheck(copt->n_sweep <= 1, comm, PETSC_ERR_USER_INPUT, "-bars takes one eps: it cannot be given with -penalty_eps0_sweep");
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The quantities of q in a fixed order, with their names and the size of their kind (the force's magnitude for its
   components and the reactions, since a component may be zero): a difference below BARS_SAME of that size is none.
   The zone's size is at index BarsSizeIndex(dim), the largest pressure at BarsPressureIndex(dim). */
static PetscInt BarsSizeIndex(PetscInt dim)
{
  return dim + 1;
}

static PetscInt BarsPressureIndex(PetscInt dim)
{
  return dim;
}

static PetscInt List(const BoundarySet *bcs, PetscInt dim, const Quantities *q, char names[][64], PetscReal v[], PetscReal kind[])
{
  PetscInt  n     = 0;
  PetscReal force = PostprocessForceMagnitude(q, dim), reactions = 0.0;

  for (PetscInt i = 0; i < bcs->n; ++i)
    for (PetscInt c = 0; c < dim; ++c) reactions += PetscSqr(q->reaction[i][c]);
  reactions = PetscMax(PetscSqrtReal(reactions), force);
  for (PetscInt c = 0; c < dim; ++c) {
    if (names) PetscSNPrintf(names[n], 64, "contact_force_%c", "xyz"[c]);
    kind[n] = force;
    v[n++]  = q->force[c];
  }
  if (names) PetscSNPrintf(names[n], 64, "pressure_max");
  kind[n] = PetscAbsReal(q->pressure_max);
  v[n++]  = q->pressure_max;
  if (names) PetscSNPrintf(names[n], 64, "contact_size");
  kind[n] = PetscAbsReal(q->contact_size);
  v[n++]  = q->contact_size;
  if (names) PetscSNPrintf(names[n], 64, "penetration_max");
  kind[n] = PetscAbsReal(q->penetration_max);
  v[n++]  = q->penetration_max;
  if (names) PetscSNPrintf(names[n], 64, "energy");
  kind[n] = PetscAbsReal(q->energy);
  v[n++]  = q->energy;
  for (PetscInt i = 0; i < bcs->n; ++i) {
    const BoundaryCondition *bc = &bcs->bc[i];

    if (bc->kind != BC_CLAMP && bc->kind != BC_SLIP) continue;
    for (PetscInt c = 0; c < dim; ++c) {
      if (names) PetscSNPrintf(names[n], 64, "reaction_%s_%s_%c", BoundaryKinds[bc->kind], bc->token, "xyz"[c]);
      kind[n] = reactions;
      v[n++]  = q->reaction[i][c];
    }
  }
  return n;
}

/* The mesh's part of one quantity from its values on the three meshes (f[0] the coarsest): the bar and the observed
   order, or NaN and the reason. */
static void MeshPart(const PetscReal f[3], PetscReal kind, PetscReal *bar, PetscReal *order, char note[], size_t len)
{
  const PetscReal e21 = f[1] - f[2], e32 = f[0] - f[1];
  const PetscReal scale = PetscMax(PetscMax(PetscMax(PetscAbsReal(f[0]), PetscAbsReal(f[1])), PetscAbsReal(f[2])), kind);

  *bar    = PETSC_NAN;
  *order  = PETSC_NAN;
  note[0] = '\0';
  if (PetscAbsReal(e21) <= BARS_SAME * scale &&
      PetscAbsReal(e32) <= BARS_SAME * scale) { /* the same on every mesh to the solves' tolerance: exact, or zero */
    *bar = 0.0;
    return;
  }
  if (e21 * e32 <= 0.0) {
    PetscSNPrintf(note, len, "not in the asymptotic range: the differences between the meshes change sign");
    return;
  }
  if (PetscAbsReal(e21) >= PetscAbsReal(e32)) {
    PetscSNPrintf(note, len, "not in the asymptotic range: the difference grows from mesh to mesh");
    return;
  }
  *order = PetscLog2Real(e32 / e21);
  if (*order < BARS_ORDER_MIN || *order > BARS_ORDER_MAX) {
    PetscSNPrintf(note, len, "not in the asymptotic range: observed order %.2f outside [%g, %g]", (double)*order, (double)BARS_ORDER_MIN,
                  (double)BARS_ORDER_MAX);
    return;
  }
  *bar = BARS_SAFETY * PetscAbsReal(e21) / (PetscPowReal(2.0, *order) - 1.0);
}

/* A quantity the mesh resolves only to a resolution r (the zone's size: the one-cell band along its edge; the largest
   nodal pressure: its step to its neighbours), f[] its values and r[] the levels' resolutions, coarsest first: the
   mesh's part where the levels are in the asymptotic range, floored at the final mesh's resolution if floored; where
   they are not but differ by no more than their resolutions (a staircase within the resolution), the last difference,
   floored the same way, and the note says so (what: the resolution's name). */
static void MeshPartResolved(const PetscReal f[3], const PetscReal r[3], PetscBool floored, const char *what, PetscReal *bar, PetscReal *order,
                             char note[], size_t len)
{
  const PetscReal e21 = f[1] - f[2], e32 = f[0] - f[1];

  MeshPart(f, PetscAbsReal(f[2]), bar, order, note, len);
  if (!PetscIsNanReal(*bar)) {
    if (floored) *bar = PetscMax(*bar, r[2]);
    return;
  }
  if (PetscAbsReal(e21) <= r[1] && PetscAbsReal(e32) <= r[0]) {
    *bar   = PetscMax(PetscAbsReal(e21), r[2]);
    *order = PETSC_NAN;
    PetscSNPrintf(note, len, "the meshes differ by less than %s: the last difference", what);
  }
}

/* The penalty's part from d = Q(eps) - Q(eps / R) with the order r: |d| (1 + 3 / (R^r - 1)). */
static PetscReal EpsPart(PetscReal d, PetscReal r)
{
  return PetscAbsReal(d) * (1.0 + BARS_SAFETY_TWO_LEVELS / (PetscPowReal(BARS_EPS_RATIO, r) - 1.0));
}

static PetscErrorCode BarsPressureBand(DM dm, const BoundarySet *bcs, Contact contact, PetscBool converged, ErrorBars *b);

/* The bars of the final mesh's quantities q, from those of the levels below it that b holds; -bars is the caller's question. */
PetscErrorCode BarsCompute(DM dm, const BoundarySet *bcs, Contact contact, const Quantities *q, PetscBool converged, ErrorBars *b)
{
  PetscInt  dim, size;
  PetscReal lv[BARS_LEVELS - 1][BARS_MAX], ev[BARS_MAX], kind[BARS_MAX], unused[BARS_MAX];

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  size = BarsSizeIndex(dim);
  b->n = List(bcs, dim, q, b->name, b->value, kind);
  for (PetscInt l = 0; l < b->nlevels; ++l) (void)List(bcs, dim, &b->level[l], NULL, lv[l], unused);
  if (b->eps_done) (void)List(bcs, dim, &b->eps_level, NULL, ev, unused);
  for (PetscInt k = 0; k < b->n; ++k) {
    if (b->nlevels < BARS_LEVELS - 1 || !converged) {
      b->bar_mesh[k] = b->order[k] = PETSC_NAN;
      PetscCall(PetscSNPrintf(b->note[k], sizeof(b->note[k]), "a solve of the three meshes failed"));
    } else {
      const PetscReal f[3] = {lv[0][k], lv[1][k], b->value[k]};

      if (k == size) {
        const PetscReal band[3] = {b->level[0].contact_size_band, b->level[1].contact_size_band, q->contact_size_band};

        MeshPartResolved(f, band, PETSC_TRUE, "the cells along the zone's edge", &b->bar_mesh[k], &b->order[k], b->note[k], sizeof(b->note[k]));
      } else if (k == BarsPressureIndex(dim)) {
        const PetscReal step[3] = {b->level[0].pressure_max_step, b->level[1].pressure_max_step, q->pressure_max_step};

        MeshPartResolved(f, step, PETSC_FALSE, "the largest pressure's step to its neighbours", &b->bar_mesh[k], &b->order[k], b->note[k],
                         sizeof(b->note[k]));
      } else
        MeshPart(f, kind[k], &b->bar_mesh[k], &b->order[k], b->note[k], sizeof(b->note[k]));
    }
    b->bar_eps[k] = 0.0;
    if (b->eps_done) {
      const PetscReal d = lv[BARS_EPS_LEVEL][k] - ev[k];

      if (PetscAbsReal(d) > BARS_SAME * PetscMax(kind[k], PetscAbsReal(lv[BARS_EPS_LEVEL][k])))
        b->bar_eps[k] = EpsPart(d, k == size ? BARS_EPS_ORDER_EDGE : BARS_EPS_ORDER);
    }
    b->bar[k] = b->bar_mesh[k] + b->bar_eps[k]; /* NaN with the mesh's part */
  }
  PetscCall(BarsPressureBand(dm, bcs, contact, converged, b));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode BarsReset(ErrorBars *b)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFree(b->pressure_levels[0]));
  PetscCall(PetscFree(b->pressure_levels[1]));
  PetscCall(PetscFree(b->pressure_bar));
  b->npressure         = 0;
  b->pressure_recorded = PETSC_FALSE;
  b->pressure_band     = PETSC_FALSE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The pressure's band, the vertex field contact_pressure_bar: on the 2h level the nodal pressure p_2h(eps) and its
   change d = p_2h(eps) - p_2h(eps / R) are kept at the vertices (p_eps[] and p_second[] over the contact set's nodes;
   p_second NULL without a penalty), the grid sequence carries them to the final mesh by the nested P1 interpolation, and
   there (BarsCompute()) each node of Gamma_C gets
     bar_i = 3 |p_h,i - p_2h(x_i)| + |d(x_i)| (1 + 3 / (R - 1)),
   the two-level index of the mesh's part with the safety factor 3 and the order 1 (a pointwise order of a profile is
   not observed: Celik et al., J. Fluids Eng. 130, 2008, report profiles with one order), and the penalty's part as for
   the quantities. Ghost vertices get their owners' values (the point SF), so every rank interpolates what it holds. */
PetscErrorCode BarsRecordPressure(DM dm, Contact contact, const PetscReal p_eps[], const PetscReal p_second[], ErrorBars *b)
{
  const ContactSet *cs;
  PetscInt          pStart, pEnd, vStart, vEnd, nroots;
  PetscReal        *chart[2];
  PetscSF           sf;

  PetscFunctionBeginUser;
  PetscCall(BarsReset(b));
  PetscCall(ContactGetSet(contact, &cs));
  PetscCall(DMPlexGetChart(dm, &pStart, &pEnd));
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  PetscCall(PetscCalloc2(pEnd - pStart, &chart[0], pEnd - pStart, &chart[1]));
  for (PetscInt i = 0; i < cs->n; ++i) {
    if (!cs->is_vertex[i]) continue;
    chart[0][cs->point[i] - pStart] = p_eps[i];
    chart[1][cs->point[i] - pStart] = p_second ? p_eps[i] - p_second[i] : 0.0;
  }
  PetscCall(DMGetPointSF(dm, &sf));
  PetscCall(PetscSFGetGraph(sf, &nroots, NULL, NULL, NULL));
  for (PetscInt k = 0; k < 2 && nroots >= 0; ++k) {
    PetscCall(PetscSFBcastBegin(sf, MPIU_REAL, chart[k], chart[k], MPI_REPLACE));
    PetscCall(PetscSFBcastEnd(sf, MPIU_REAL, chart[k], chart[k], MPI_REPLACE));
  }
  for (PetscInt k = 0; k < 2; ++k) {
    PetscCall(PetscMalloc1(vEnd - vStart, &b->pressure_levels[k]));
    PetscCall(PetscArraycpy(b->pressure_levels[k], chart[k] + (vStart - pStart), vEnd - vStart));
  }
  PetscCall(PetscFree2(chart[0], chart[1]));
  b->pressure_recorded = PETSC_TRUE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* -bars on the Gmsh model's remeshed levels (GridSequenceRemeshHalf()): the 2h level's pressure and its change at
   eps / R, kept at the vertices, carried to the next mesh by the remeshing's transfer (MeshTransferCreateFromField():
   each new vertex takes the P1 field of the old cell that holds it), as the nested levels' interpolation carries them.
   The two values ride in the first two components of a vector of the displacement's layout. The fields are zero off
   Gamma_C, so that a new vertex of the curved boundary, a sagitta h^2 / 8R off the old chords, takes a share of the
   interior's zero of the order of h / 8R. */
PetscErrorCode BarsPressureTransferCreate(DM dm, const ErrorBars *b, Vec loc, MeshTransfer *tr)
{
  PetscSection sec;
  PetscInt     vStart, vEnd;
  PetscScalar *a;
  Vec          field;

  PetscFunctionBeginUser;
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  PetscCall(DMGetLocalSection(dm, &sec));
  PetscCall(VecDuplicate(loc, &field));
  PetscCall(VecSet(field, 0.0));
  PetscCall(VecGetArray(field, &a));
  for (PetscInt v = vStart; v < vEnd; ++v) {
    PetscInt ndof, off;

    PetscCall(PetscSectionGetDof(sec, v, &ndof));
    PetscCall(PetscSectionGetOffset(sec, v, &off));
    for (PetscInt k = 0; k < 2 && k < ndof; ++k) a[off + k] = b->pressure_levels[k][v - vStart];
  }
  PetscCall(VecRestoreArray(field, &a));
  PetscCall(MeshTransferCreateFromField(dm, field, tr));
  PetscCall(VecDestroy(&field));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode BarsPressureTransferApply(DM fine, ErrorBars *b, Vec fine_loc, MeshTransfer *tr)
{
  PetscSection       sec;
  PetscInt           vStart, vEnd;
  const PetscScalar *a;
  Vec                field;

  PetscFunctionBeginUser;
  PetscCall(VecDuplicate(fine_loc, &field));
  PetscCall(VecSet(field, 0.0));
  PetscCall(MeshTransferApply(*tr, fine, field));
  PetscCall(MeshTransferDestroy(tr));
  PetscCall(DMPlexGetDepthStratum(fine, 0, &vStart, &vEnd));
  PetscCall(DMGetLocalSection(fine, &sec));
  PetscCall(VecGetArrayRead(field, &a));
  for (PetscInt k = 0; k < 2; ++k) {
    PetscCall(PetscFree(b->pressure_levels[k]));
    PetscCall(PetscCalloc1(vEnd - vStart + 1, &b->pressure_levels[k]));
  }
  for (PetscInt v = vStart; v < vEnd; ++v) {
    PetscInt ndof, off;

    PetscCall(PetscSectionGetDof(sec, v, &ndof));
    PetscCall(PetscSectionGetOffset(sec, v, &off));
    for (PetscInt k = 0; k < 2 && k < ndof; ++k) b->pressure_levels[k][v - vStart] = PetscRealPart(a[off + k]);
  }
  PetscCall(VecRestoreArrayRead(field, &a));
  PetscCall(VecDestroy(&field));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The band at each node over its neighbours on Gamma_C: the largest of the node's own and of the nodes it shares a
   contact face with. A node's own two-level difference |p_h - p_2h| vanishes where the two profiles cross, which they
   do near the zone's edge, while its error does not; the neighbours' largest covers it (docs/estimate.md, "The
   pressure's band", measures both against a fine SNESVI profile). chart[] holds the band at every point
   of the chart (-1 where none), the owners' values at the ghosts; the result is the same on every rank. */
static PetscErrorCode BandOverNeighbours(DM dm, const BoundarySet *bcs, PetscReal chart[])
{
  DMLabel    sets;
  PetscSF    sf;
  PetscInt   pStart, pEnd, vStart, vEnd, nroots;
  PetscReal *wide;

  PetscFunctionBeginUser;
  PetscCall(DMPlexGetChart(dm, &pStart, &pEnd));
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  PetscCall(DMGetLabel(dm, "Face Sets", &sets));
  PetscCall(DMGetPointSF(dm, &sf));
  PetscCall(PetscSFGetGraph(sf, &nroots, NULL, NULL, NULL));
  if (nroots >= 0) { /* the owners' bands at the ghosts */
    PetscCall(PetscSFBcastBegin(sf, MPIU_REAL, chart, chart, MPI_REPLACE));
    PetscCall(PetscSFBcastEnd(sf, MPIU_REAL, chart, chart, MPI_REPLACE));
  }
  PetscCall(PetscMalloc1(pEnd - pStart, &wide));
  PetscCall(PetscArraycpy(wide, chart, pEnd - pStart));
  for (PetscInt k = 0; k < bcs->ncontact && sets; ++k) {
    IS              is;
    const PetscInt *faces;
    PetscInt        nf;

    PetscCall(DMLabelGetStratumIS(sets, bcs->contact_ids[k], &is));
    if (!is) continue;
    PetscCall(ISGetLocalSize(is, &nf));
    PetscCall(ISGetIndices(is, &faces));
    for (PetscInt i = 0; i < nf; ++i) {
      PetscInt *closure = NULL, ncl;
      PetscReal most    = -1.0;

      PetscCall(DMPlexGetTransitiveClosure(dm, faces[i], PETSC_TRUE, &ncl, &closure));
      for (PetscInt j = 0; j < ncl; ++j)
        if (closure[2 * j] >= vStart && closure[2 * j] < vEnd) most = PetscMax(most, chart[closure[2 * j] - pStart]);
      for (PetscInt j = 0; j < ncl; ++j)
        if (closure[2 * j] >= vStart && closure[2 * j] < vEnd && chart[closure[2 * j] - pStart] >= 0.0)
          wide[closure[2 * j] - pStart] = PetscMax(wide[closure[2 * j] - pStart], most);
      PetscCall(DMPlexRestoreTransitiveClosure(dm, faces[i], PETSC_TRUE, &ncl, &closure));
    }
    PetscCall(ISRestoreIndices(is, &faces));
    PetscCall(ISDestroy(&is));
  }
  if (nroots >= 0) { /* a node's neighbours on other ranks: the largest over the ranks, at the owner and back */
    PetscCall(PetscSFReduceBegin(sf, MPIU_REAL, wide, wide, MPI_MAX));
    PetscCall(PetscSFReduceEnd(sf, MPIU_REAL, wide, wide, MPI_MAX));
    PetscCall(PetscSFBcastBegin(sf, MPIU_REAL, wide, wide, MPI_REPLACE));
    PetscCall(PetscSFBcastEnd(sf, MPIU_REAL, wide, wide, MPI_REPLACE));
  }
  PetscCall(PetscArraycpy(chart, wide, pEnd - pStart));
  PetscCall(PetscFree(wide));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The band at the final mesh's contact nodes, from the values the grid sequence carried there (none unless the three
   meshes converged). */
static PetscErrorCode BarsPressureBand(DM dm, const BoundarySet *bcs, Contact contact, PetscBool converged, ErrorBars *b)
{
  const ContactSet *cs;
  PetscInt          vStart, vEnd;

  PetscFunctionBeginUser;
  PetscCall(ContactGetSet(contact, &cs));
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  b->pressure_band = (PetscBool)(b->pressure_recorded && converged && b->nlevels == BARS_LEVELS - 1);
  if (b->pressure_band) {
    PetscInt   pStart, pEnd;
    PetscReal *chart;

    b->npressure = cs->n;
    PetscCall(PetscMalloc1(cs->n, &b->pressure_bar));
    PetscCall(DMPlexGetChart(dm, &pStart, &pEnd));
    PetscCall(PetscMalloc1(pEnd - pStart, &chart));
    for (PetscInt p = 0; p < pEnd - pStart; ++p) chart[p] = -1.0;
    for (PetscInt i = 0; i < cs->n; ++i) {
      const PetscInt v = cs->point[i] - vStart;

      if (cs->is_vertex[i])
        chart[cs->point[i] - pStart] =
            BARS_SAFETY_TWO_LEVELS * PetscAbsReal(cs->pressure[i] - b->pressure_levels[0][v]) + EpsPart(b->pressure_levels[1][v], BARS_EPS_ORDER);
    }
    PetscCall(BandOverNeighbours(dm, bcs, chart));
    for (PetscInt i = 0; i < cs->n; ++i)
      b->pressure_bar[i] = cs->is_vertex[i] ? chart[cs->point[i] - pStart] : PETSC_NAN; /* NaN: not a vertex (P2) */
    PetscCall(PetscFree(chart));
  }
  PetscCall(PetscFree(b->pressure_levels[0]));
  PetscCall(PetscFree(b->pressure_levels[1]));
  b->pressure_recorded = PETSC_FALSE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The summary's lines: each quantity with its bar, its parts and the observed order, or the reason for none. */
PetscErrorCode BarsView(MPI_Comm comm, const ErrorBars *b)
{
  PetscFunctionBeginUser;
  if (!b->n) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscPrintf(comm, "  error bars (mesh: %s, h to 4h, grid convergence index; eps: a second solve at eps/%d on 2h):\n",
                        b->remeshed ? "three meshes of the Gmsh model (-adapt_model) at halved sizes" : "three nested meshes", (int)BARS_EPS_RATIO));
  for (PetscInt k = 0; k < b->n; ++k) {
    if (PetscIsNanReal(b->bar[k]))
      PetscCall(PetscPrintf(comm, "    %-24s %.6g, no bar: %s\n", b->name[k], (double)b->value[k], b->note[k]));
    else if (PetscIsNanReal(b->order[k]) && b->note[k][0])
      PetscCall(PetscPrintf(comm, "    %-24s %.6g +- %.2g (mesh %.2g, eps %.2g; %s)\n", b->name[k], (double)b->value[k], (double)b->bar[k],
                            (double)b->bar_mesh[k], (double)b->bar_eps[k], b->note[k]));
    else if (PetscIsNanReal(b->order[k]))
      PetscCall(PetscPrintf(comm, "    %-24s %.6g +- %.2g (mesh %.2g, eps %.2g; the same on the three meshes)\n", b->name[k], (double)b->value[k],
                            (double)b->bar[k], (double)b->bar_mesh[k], (double)b->bar_eps[k]));
    else
      PetscCall(PetscPrintf(comm, "    %-24s %.6g +- %.2g (mesh %.2g, eps %.2g; observed order %.2f)\n", b->name[k], (double)b->value[k],
                            (double)b->bar[k], (double)b->bar_mesh[k], (double)b->bar_eps[k], (double)b->order[k]));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* -bars in /run: for each quantity NAME, qoi_NAME, its bar, the bar's two parts and the observed order (where each is
   known), or qoi_NAME_note saying why there is no bar. */
PetscErrorCode BarsWrite(const ErrorBars *b, PetscViewer v)
{
  const char *suffix[] = {"", "_bar", "_bar_mesh", "_bar_eps", "_order"};

  PetscFunctionBeginUser;
  for (PetscInt k = 0; k < b->n; ++k) {
    const PetscReal values[] = {b->value[k], b->bar[k], b->bar_mesh[k], b->bar_eps[k], b->order[k]};

    for (PetscInt j = 0; j < 5; ++j)
      if (!PetscIsNanReal(values[j])) PetscCall(RunAttrReal(v, values[j], "qoi_%s%s", b->name[k], suffix[j]));
    if (b->note[k][0]) PetscCall(RunAttrString(v, b->note[k], "qoi_%s_note", b->name[k]));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

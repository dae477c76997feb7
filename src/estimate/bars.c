/* Error bars of the quantities users read (-bars): the contact force, the largest pressure, the contact zone's size, the
   largest penetration, the energy and the supports' reactions.

   The mesh's part. The grid sequence solves the problem on nested meshes h1 = h (the final one), h2 = 2h, h3 = 4h, all
   at the final mesh's eps and to the final tolerance (src/solver/grid_sequence.c), so that a quantity Q differs between
   them by its discretization error alone. If Q(h) = Q* + C h^p, the differences e21 = Q2 - Q1 and e32 = Q3 - Q2 have
   the ratio e21 / e32 = 2^-p, which gives the observed order p, and Richardson's extrapolation the error of Q1,
   e21 / (2^p - 1). Roache's grid convergence index (J. Fluids Eng. 116, 1994; ASME V&V 20-2009, section 2.4) multiplies
   it by the safety factor 1.25 of a three-mesh study:
     bar_mesh = 1.25 |e21| / (2^p - 1).
   Where the three meshes are not in the asymptotic range the formula means nothing, and no bar is given, with the
   reason: the differences change sign (oscillatory convergence), or grow (divergence), or give an order outside
   [BARS_ORDER_MIN, BARS_ORDER_MAX] (a P1 quantity converges at an order between about 1/2, a pressure peak at a kink,
   and 2, a smooth functional; outside a wider range the ratio of two differences is noise).
   The penalty's part. With the active set fixed, the penalty solution is affine in eps to first order, so
   Q(eps) - Q(0) ~ (Q(eps) - Q(eps / R)) R / (R - 1), R = BARS_EPS_RATIO, measured on the coarsest of the three meshes,
   which is cheap and has the same eps (the penalty error of Q depends on h only through the discretization).
   The bar is their sum, bar_mesh + bar_eps. */
#include "contact.h"
#include "estimate.h"
#include "physics.h"

#define BARS_SAFETY 1.25
#define BARS_ORDER_MIN 0.3
#define BARS_ORDER_MAX 5.0

/* -bars needs three nested meshes and one eps; refused before the solve otherwise. */
PetscErrorCode BarsCheck(MPI_Comm comm, const AppCtx *user)
{
  const PetscInt        nlevels = user->box.coarse_levels + user->opt->solver.grid_sequence;
  const ContactOptions *copt;

  PetscFunctionBeginUser;
  if (!user->opt->bars) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(ContactGetOptions(user->contact, &copt));
  PetscCheck(nlevels >= BARS_LEVELS - 1, comm, PETSC_ERR_USER_INPUT,
             "-bars needs the solutions on three nested meshes, and this run solves %" PetscInt_FMT
             ": give -contact_grid_sequence 2 (the mesh of the options and two uniform refinements of it), or on a box -contact_coarse_levels 2",
             nlevels + 1);
  PetscCheck(copt->n_sweep <= 1, comm, PETSC_ERR_USER_INPUT, "-bars takes one eps: it cannot be given with -penalty_eps0_sweep");
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The quantities of q in a fixed order, with their names and the size of their kind (the force's magnitude for its
   components and the reactions, since a component may be zero): a difference below round-off of that size is none. */
static PetscInt List(const AppCtx *user, PetscInt dim, const Quantities *q, char names[][64], PetscReal v[], PetscReal kind[])
{
  PetscInt  n     = 0;
  PetscReal force = 0.0, reactions = 0.0;

  for (PetscInt c = 0; c < dim; ++c) force += PetscSqr(q->force[c]);
  for (PetscInt i = 0; i < user->scene.bcs.n; ++i)
    for (PetscInt c = 0; c < dim; ++c) reactions += PetscSqr(q->reaction[i][c]);
  force     = PetscSqrtReal(force);
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
  for (PetscInt i = 0; i < user->scene.bcs.n; ++i) {
    const BoundaryCondition *bc = &user->scene.bcs.bc[i];

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
  if (PetscAbsReal(e21) <= 1e-10 * scale && PetscAbsReal(e32) <= 1e-10 * scale) { /* the same on every mesh to round-off: exact, or zero */
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

PetscErrorCode BarsCompute(DM dm, AppCtx *user)
{
  ErrorBars *b = &user->rec.bars;
  Quantities q;
  PetscInt   dim;
  PetscReal  lv[BARS_LEVELS - 1][BARS_MAX], ev[BARS_MAX], kind[BARS_MAX], unused[BARS_MAX];

  PetscFunctionBeginUser;
  b->n = 0;
  if (!user->opt->bars) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(DMGetDimension(dm, &dim));
  PostprocessGetQuantities(user, &q); /* the final mesh's */
  b->n = List(user, dim, &q, b->name, b->value, kind);
  for (PetscInt l = 0; l < b->nlevels; ++l) (void)List(user, dim, &b->level[l], NULL, lv[l], unused);
  if (b->eps_done) (void)List(user, dim, &b->eps_level, NULL, ev, unused);
  for (PetscInt k = 0; k < b->n; ++k) {
    if (b->nlevels < BARS_LEVELS - 1 || !user->rec.stats.converged) {
      b->bar_mesh[k] = b->order[k] = PETSC_NAN;
      PetscCall(PetscSNPrintf(b->note[k], sizeof(b->note[k]), "a solve of the three meshes failed"));
    } else {
      const PetscReal f[3] = {lv[0][k], lv[1][k], b->value[k]};

      MeshPart(f, kind[k], &b->bar_mesh[k], &b->order[k], b->note[k], sizeof(b->note[k]));
    }
    b->bar_eps[k] = b->eps_done ? PetscAbsReal(lv[0][k] - ev[k]) * BARS_EPS_RATIO / (BARS_EPS_RATIO - 1.0) : 0.0;
    if (b->bar_eps[k] <= 1e-10 * PetscMax(kind[k], PetscAbsReal(lv[0][k]))) b->bar_eps[k] = 0.0; /* round-off */
    b->bar[k] = b->bar_mesh[k] + b->bar_eps[k];                                                  /* NaN with the mesh's part */
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The summary's lines: each quantity with its bar, its parts and the observed order, or the reason for none. */
PetscErrorCode BarsView(MPI_Comm comm, const ErrorBars *b)
{
  PetscFunctionBeginUser;
  if (!b->n) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscPrintf(comm, "  error bars (mesh: three nested meshes, h to 4h, grid convergence index; eps: a second solve at eps/%d):\n",
                        (int)BARS_EPS_RATIO));
  for (PetscInt k = 0; k < b->n; ++k) {
    if (PetscIsNanReal(b->bar[k]))
      PetscCall(PetscPrintf(comm, "    %-24s %.6g, no bar: %s\n", b->name[k], (double)b->value[k], b->note[k]));
    else if (PetscIsNanReal(b->order[k]))
      PetscCall(PetscPrintf(comm, "    %-24s %.6g +- %.2g (mesh %.2g, eps %.2g; the same on the three meshes)\n", b->name[k], (double)b->value[k],
                            (double)b->bar[k], (double)b->bar_mesh[k], (double)b->bar_eps[k]));
    else
      PetscCall(PetscPrintf(comm, "    %-24s %.6g +- %.2g (mesh %.2g, eps %.2g; observed order %.2f)\n", b->name[k], (double)b->value[k],
                            (double)b->bar[k], (double)b->bar_mesh[k], (double)b->bar_eps[k], (double)b->order[k]));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

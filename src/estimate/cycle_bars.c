/* Error bars of the quantities on the meshes of the adaptive refinement (-accuracy, src/drivers/adapt.c).

   The meshes of the cycles are nested but not uniformly refined, so that -bars' three levels h, 2h, 4h do not exist.
   Their place is taken by the cycles themselves, each with the size h_k = N_k^(-1/dim) of its N_k unknowns (the size
   of a uniform mesh with as many unknowns; an adapted mesh of N unknowns converges in N as a uniform one does in h when
   the refinement follows the error, Binev, Dahmen, DeVore, Numer. Math. 97, 2004). For the last cycle k:
   - j is the last cycle with at most N_k / 2^dim unknowns (h_j >= 2 h_k);
   - j and the cycle before it, m = j and j - 1, each give Roache's two-level grid convergence index with the safety
     factor 3 (the one for a study whose order is not observed, and for refinement that is not uniform) and the order
     r of the quantity's slowest part:
       bar_m = 3 |Q_m - Q_k| / ((h_m / h_k)^r - 1),
     and the bar is the larger of the two, so that one cycle that happens to fall near the last one does not make the
     bar small; there is no bar before both exist.
   r = 1 for the force and the largest pressure: eps follows h and the penalty's error is of order eps, as the mesh's
   is of h for the largest pressure at a kink of the profile. r = 1/2 for the zone's size, as -bars' penalty part takes
   it (src/estimate/bars.c): its free edge moves like eps^(1/2) or faster.
   The cycles' differences mix the contact zone's refinement with the far field's, and their ratios are not an order:
   the order is the theory's, not observed.
   The penalty is part of each cycle's discretization: eps follows the smallest contact cell's size
   (MeshSetContactCellSizes()), and the penalty's error falls with it as the mesh's does; the differences between the
   cycles hold both.
   The force's two parts apart, where the cycles have their force at eps / R too (R = CYCLE_EPS_RATIO; -accuracy on the
   force with the penalty method, src/drivers/adapt.c): the penalty's part of cycle k is bounded as -bars bounds it
   (src/estimate/bars.c), d = F(eps) - F(eps / R) and bar_eps = |d| (1 + 3 / (R - 1)) at the order 1 in eps; the
   mesh's part compares the cycles' forces extrapolated to eps = 0, F0 = (R F(eps / R) - F(eps)) / (R - 1), at the
   order 2 of the force's mesh error (a functional of the displacement), with the same two cycles and safety factor 3;
   the bar is the sum. F(eps / R) is the tangent's prediction (one linear solve).
   The largest pressure's bar adds its penalty part on the cycle's own mesh to the index at the order 1, where the
   cycle has its pressure at eps / R: |p(eps) - p(eps / R)| (1 + 3 / (R - 1)). The nodal maximum moves between the
   cycles with its node's place as well as with the error, so that the index alone can fall below the error; the
   penalty's part does not depend on where the nodes fall.
   The zone's size's two parts apart, where eps <= h / (10 M) (CYCLE_SMALL_EPS; -accuracy's default eps0 = 0.1) and the
   cycle has its size at eps / R (the same tangent's state): the penalty's part bounded as -bars bounds it, d = W(eps) -
   W(eps / R) and bar_eps = |d| (1 + 3 / (R^(1/2) - 1)) at the order 1/2 in eps; the mesh's part the index above on the
   cycles' sizes at the order 1 (the linear interpolant's zero crossing puts the free edge within a fraction of its cell);
   the bar is the sum. At eps = h the parts are not apart: the penalty's fringe at the zone's edge spans cells, and the
   size's error falls like h^(1/2) as a whole.
   The zone's size is resolved to a cell: its bar is at least the one-cell band along its edge (contact_size_band).
   The largest pressure is resolved to its node's cells: its bar is at least the change of the nodal pressure from its
   node to its neighbours on Gamma_C (pressure_max_step, src/physics/contact_zone.c), which bounds the nodal value's
   error of order h where the maximum sits on a slope (the manufactured solution's, at the end of Gamma_C).
   The recovered peak (pressure_peak, src/physics/pressure_peak.c) is a least-squares fit to scattered nodal values,
   with a standard error (its resolution) that the fit itself gives. The index on its whole changes would triple that
   scatter, so its bar counts each change only beyond twice its standard deviation (the two fits' resolutions), as a
   change that is significant, adds its penalty part, and adds twice the last fit's resolution for the scatter of its
   own value (PeakBar()).
   The energy's bar is the error estimate itself, against the solution's energy norm (src/estimate/estimate.c).
   What each choice was measured against, and what was tried before it: docs/decisions.md, "The bars of -accuracy's
   cycles". */
#include "estimate.h"
#include "physics.h"

#define CYCLE_SAFETY 3.0          /* Roache's safety factor of a two-level study whose order comes from theory */
#define CYCLE_RATIO 2.0           /* the cycles compared differ by at least this ratio of h_k = N_k^(-1/dim) */
#define CYCLE_ORDER 1.0           /* the order in h of the force and the largest pressure */
#define CYCLE_ORDER_SIZE 0.5      /*   and of the zone's size */
#define CYCLE_ORDER_FORCE 2.0     /* the order in h of the force's mesh part, its penalty part apart */
#define CYCLE_ORDER_SIZE_MESH 1.0 /*   and of the zone's size's mesh part, its penalty part apart, */
#define CYCLE_SMALL_EPS 0.1       /*   where eps is at most this fraction of its scale h/M */
#define CYCLE_PEAK_NOISE 2.0      /* the recovered peak's changes count beyond this many of their deviations; its bar holds as many of its own */

const char *const AccuracyQuantities[] = {"energy",        "contact_force",    "pressure_max", "contact_size",
                                          "pressure_peak", "AccuracyQuantity", "ACCURACY_",    NULL};

/* The last cycle before `last` whose size is at least CYCLE_RATIO times cycle last's, or -1. */
static PetscInt Coarser(const CycleRecord c[], PetscInt last, PetscInt dim)
{
  for (PetscInt m = last - 1; m >= 0; --m)
    if ((PetscReal)c[m].n_dofs * PetscPowReal(CYCLE_RATIO, dim) <= (PetscReal)c[last].n_dofs * (1.0 + 1e-12)) return m;
  return -1;
}

static PetscReal Size(const CycleRecord *c, PetscInt dim)
{
  return PetscPowReal((PetscReal)c->n_dofs, -1.0 / dim);
}

/* Roache's two-level index of the last cycle against cycle m, from the change of a quantity between them, at the order r. */
static PetscReal Index(const CycleRecord c[], PetscInt m, PetscInt last, PetscInt dim, PetscReal change, PetscReal r)
{
  return CYCLE_SAFETY * change / (PetscPowReal(Size(&c[m], dim) / Size(&c[last], dim), r) - 1.0);
}

/* The bar of quantity k on the last cycle, NaN before the cycle twice as coarse and the one before it exist; r its order. */
static PetscReal Bar(const CycleRecord c[], PetscInt k, PetscInt last, PetscInt dim, PetscReal r)
{
  const PetscInt j   = Coarser(c, last, dim);
  PetscReal      bar = 0.0;

  if (j < 1) return PETSC_NAN;
  for (PetscInt m = j; m >= j - 1; --m) bar = PetscMax(bar, Index(c, m, last, dim, PetscAbsReal(c[m].value[k] - c[last].value[k]), r));
  return bar;
}

/* The penalty's part of quantity k on cycle c, bounded as -bars bounds it from its value at eps / R on the same mesh, at
   the order r in eps: |Q(eps) - Q(eps / R)| (1 + 3 / (R^r - 1)); NaN without that value. */
static PetscReal PenaltyPart(const CycleRecord *c, PetscInt k, PetscReal r)
{
  return PetscAbsReal(c->value[k] - c->value_eps[k]) * (1.0 + CYCLE_SAFETY / (PetscPowReal(CYCLE_EPS_RATIO, r) - 1.0));
}

/* The force's bar from its mesh and penalty parts (above), NaN unless the last cycle, the one twice as coarse and the
   one before it have their force at eps / R. */
static PetscReal ForceBar(const CycleRecord c[], PetscInt last, PetscInt dim)
{
  const PetscInt  j = Coarser(c, last, dim), k = ACCURACY_FORCE;
  const PetscReal R    = CYCLE_EPS_RATIO;
  PetscReal       mesh = 0.0, f0_last;

  if (j < 1 || PetscIsNanReal(c[last].value_eps[k]) || PetscIsNanReal(c[j].value_eps[k]) || PetscIsNanReal(c[j - 1].value_eps[k])) return PETSC_NAN;
  f0_last = (R * c[last].value_eps[k] - c[last].value[k]) / (R - 1.0);
  for (PetscInt m = j; m >= j - 1; --m) {
    const PetscReal f0 = (R * c[m].value_eps[k] - c[m].value[k]) / (R - 1.0);

    mesh = PetscMax(mesh, Index(c, m, last, dim, PetscAbsReal(f0 - f0_last), CYCLE_ORDER_FORCE));
  }
  return mesh + PenaltyPart(&c[last], k, 1.0);
}

/* The largest nodal pressure's bar: the index at the order 1 plus its penalty part on the last cycle's mesh (above), NaN
   before the cycles compared exist or without its value at eps / R. */
static PetscReal PressureBar(const CycleRecord c[], PetscInt last, PetscInt dim)
{
  return Bar(c, ACCURACY_PRESSURE, last, dim, CYCLE_ORDER) + PenaltyPart(&c[last], ACCURACY_PRESSURE, 1.0);
}

/* The recovered peak's bar: the index on the part of each change beyond CYCLE_PEAK_NOISE of its standard deviation (the
   two fits' resolutions, independent scatters), plus its penalty part where the last cycle has its value at eps / R,
   plus CYCLE_PEAK_NOISE of the last fit's own resolution; NaN before the cycles compared exist. */
static PetscReal PeakBar(const CycleRecord c[], PetscInt last, PetscInt dim)
{
  const PetscInt  j = Coarser(c, last, dim), k = ACCURACY_PEAK;
  const PetscReal res = c[last].q.pressure_peak_resolution, penalty = PenaltyPart(&c[last], k, 1.0);
  PetscReal       index = 0.0;

  if (j < 1) return PETSC_NAN;
  for (PetscInt m = j; m >= j - 1; --m) {
    const PetscReal noise  = CYCLE_PEAK_NOISE * PetscSqrtReal(PetscSqr(c[m].q.pressure_peak_resolution) + PetscSqr(res)),
                    change = PetscMax(PetscAbsReal(c[m].value[k] - c[last].value[k]) - noise, 0.0);

    index = PetscMax(index, Index(c, m, last, dim, change, CYCLE_ORDER));
  }
  return index + (PetscIsNanReal(penalty) ? 0.0 : penalty) + CYCLE_PEAK_NOISE * res;
}

/* The zone's size's bar from its penalty and mesh parts (above), NaN unless the last cycle has its size at eps / R, its
   eps is small (CYCLE_SMALL_EPS), and the cycles compared exist. */
static PetscReal SizeBar(const CycleRecord c[], PetscInt last, PetscInt dim)
{
  if (!(c[last].eps <= CYCLE_SMALL_EPS * c[last].eps_scale * (1.0 + 1e-12))) return PETSC_NAN;
  return Bar(c, ACCURACY_SIZE, last, dim, CYCLE_ORDER_SIZE_MESH) + PenaltyPart(&c[last], ACCURACY_SIZE, CYCLE_ORDER_SIZE);
}

/* The penalty's part of quantity k's bar on cycle c, NaN where the cycle has no value at eps / R; for the energy, the
   estimate's penalty part. At a fixed eps (-penalty_eps) it tends to the penalty problem's own error as the mesh is
   refined, and no refinement takes it below the tolerance (adapt.c). */
PetscReal CycleBarsPenaltyPart(const CycleRecord *c, PetscInt k)
{
  if (k == ACCURACY_ENERGY) return c->estimate_penalty;
  return PenaltyPart(c, k, k == ACCURACY_SIZE ? CYCLE_ORDER_SIZE : 1.0);
}

/* The last cycle's values and bars; the earlier cycles' values are those of the earlier calls, one per cycle. */
PetscErrorCode CycleBarsCompute(CycleRecord cycles[], PetscInt dim, PetscInt last)
{
  CycleRecord *c = &cycles[last];

  PetscFunctionBeginUser;
  c->value[ACCURACY_ENERGY]   = c->norm;
  c->value[ACCURACY_FORCE]    = PostprocessForceMagnitude(&c->q, dim);
  c->value[ACCURACY_PRESSURE] = c->q.pressure_max;
  c->value[ACCURACY_SIZE]     = c->q.contact_size;
  c->value[ACCURACY_PEAK]     = c->q.pressure_peak;
  c->bar[ACCURACY_ENERGY]     = c->estimate;
  for (PetscInt k = ACCURACY_FORCE; k < ACCURACY_NUM; ++k) c->bar[k] = Bar(cycles, k, last, dim, k == ACCURACY_SIZE ? CYCLE_ORDER_SIZE : CYCLE_ORDER);
  {
    const PetscReal force = ForceBar(cycles, last, dim), pressure = PressureBar(cycles, last, dim), size = SizeBar(cycles, last, dim),
                    peak = PeakBar(cycles, last, dim);

    if (!PetscIsNanReal(force)) c->bar[ACCURACY_FORCE] = force;
    if (!PetscIsNanReal(pressure)) c->bar[ACCURACY_PRESSURE] = pressure;
    if (!PetscIsNanReal(size)) c->bar[ACCURACY_SIZE] = size;
    if (!PetscIsNanReal(peak)) c->bar[ACCURACY_PEAK] = peak;
  }
  if (!PetscIsNanReal(c->bar[ACCURACY_SIZE])) c->bar[ACCURACY_SIZE] = PetscMax(c->bar[ACCURACY_SIZE], c->q.contact_size_band);
  if (!PetscIsNanReal(c->bar[ACCURACY_PRESSURE])) c->bar[ACCURACY_PRESSURE] = PetscMax(c->bar[ACCURACY_PRESSURE], c->q.pressure_max_step);
  PetscFunctionReturn(PETSC_SUCCESS);
}

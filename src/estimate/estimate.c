/* The a posteriori error estimate of a run: its option, the geometry of the P1 simplices it walks, and the sum of the
   parts (estimate_residual.c: the residual of the equilibrium, estimate_penalty.c: the penalty's consistency error).

   For P1 elements sigma(u_h) is constant in each cell, and the residual of the discrete problem is carried by the body
   force inside the cells and by the tractions on the faces: the jumps [sigma(u_h) n] across interior faces, the misfit
   t - sigma(u_h) n on the loaded and free faces, and on Gamma_C the misfit of sigma(u_h) n with the traction -p_h n the
   obstacle exerts. The classical residual estimator of linear elasticity (Verfurth, "A posteriori error estimation
   techniques", 2013, section 1.4 and 4.2) bounds the energy-norm error by the h-weighted norms of these, divided by 2 mu
   to have the energy's units; for contact the same face terms with the contact traction (Hild and Nicaise, M2AN 41
   (2007); Chouly, Fabre, Hild, Pousin, Renard, hal-01143168, for Nitsche's method), plus the error of the contact law
   itself, which for the penalty method is its penetration (estimate_penalty.c). */
#include "app.h"
#include "contact.h"
#include "estimate_impl.h"
#include "physics.h"
#include "verify.h"

const char *const EstimateParts[] = {"bulk", "jump", "neumann", "contact_normal", "contact_tangential", "penalty", "EstimatePart", "ESTIMATE_", NULL};

PetscErrorCode EstimateGetOptions(MPI_Comm comm, RunOptions *opt)
{
  PetscFunctionBeginUser;
  PetscOptionsBegin(comm, NULL, "A posteriori error estimate", "Signorini");
  opt->estimate = PETSC_TRUE;
  PetscCall(PetscOptionsBool("-estimate", "Estimate the energy-norm error of the solution, cell by cell (P1 simplices)", "EstimateCompute",
                             opt->estimate, &opt->estimate, &opt->estimate_given));
  opt->bars = PETSC_FALSE;
  PetscCall(PetscOptionsBool("-bars", "Error bars of the force, pressure, contact size, penetration, energy and reactions (three nested meshes)",
                             "BarsCompute", opt->bars, &opt->bars, NULL));
  PetscOptionsEnd();
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Whether the estimator applies: P1 on simplices; *why says what else the discretization is. */
static PetscErrorCode Supported(DM dm, PetscInt degree, PetscBool *ok, char why[], size_t len)
{
  PetscInt       dim, cStart, cEnd, simplex = 1, all;
  DMPolytopeType ct;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  if (cEnd > cStart) {
    PetscCall(DMPlexGetCellType(dm, cStart, &ct));
    simplex = DMPolytopeTypeGetNumVertices(ct) == dim + 1;
  }
  PetscCall(MPIU_Allreduce(&simplex, &all, 1, MPIU_INT, MPI_MIN, PetscObjectComm((PetscObject)dm)));
  *ok = (PetscBool)(all && degree == 1);
  if (degree != 1)
    PetscCall(PetscSNPrintf(why, len, "implemented for P1, not P%" PetscInt_FMT, degree));
  else if (!all)
    PetscCall(PetscSNPrintf(why, len, "implemented for simplices (triangles, tetrahedra), not %s", dim == 2 ? "quadrilaterals" : "hexahedra"));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* -estimate given on a discretization the estimator does not cover is refused before the solve; by default such a run
   goes without the estimate, and the summary says why. */
PetscErrorCode EstimateCheckSupported(DM dm, PetscBool estimate, PetscBool estimate_given, PetscInt degree)
{
  PetscBool ok;
  char      why[128] = "";

  PetscFunctionBeginUser;
  if (!estimate || !estimate_given) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(Supported(dm, degree, &ok, why, sizeof(why)));
  PetscCheck(ok, PetscObjectComm((PetscObject)dm), PETSC_ERR_USER_INPUT,
             "-estimate: the error estimate is %s; run without -estimate (or with -estimate false)", why);
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode EstimateReset(ErrorEstimate *est)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFree2(est->cell, est->density));
  est->computed       = PETSC_FALSE;
  est->unavailable[0] = '\0';
  est->total          = PETSC_NAN;
  est->norm           = PETSC_NAN;
  for (PetscInt k = 0; k < ESTIMATE_NUM_PARTS; ++k) est->part[k] = PETSC_NAN;
  est->ncells = 0;
  est->time   = 0.0;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* A Gauss rule with npts points per direction on the reference simplex of dimension sdim (Stroud's conical product),
   in barycentric coordinates. */
static PetscErrorCode RuleCreate(PetscInt sdim, PetscInt npts, EstimateRule *rule)
{
  PetscQuadrature  q;
  const PetscReal *pts, *wts;
  PetscInt         n;
  PetscReal        sum = 0.0;

  PetscFunctionBeginUser;
  PetscCall(PetscDTStroudConicalQuadrature(sdim, 1, npts, -1.0, 1.0, &q));
  PetscCall(PetscQuadratureGetData(q, NULL, NULL, &n, &pts, &wts));
  rule->n  = n;
  rule->nb = sdim + 1;
  PetscCall(PetscMalloc2(n * rule->nb, &rule->bary, n, &rule->w));
  for (PetscInt i = 0; i < n; ++i) sum += wts[i];
  for (PetscInt i = 0; i < n; ++i) { /* the reference simplex has vertices -1 and e_k: lambda_k = (xi_k + 1) / 2 */
    PetscReal *b = &rule->bary[i * rule->nb];

    b[0] = 1.0;
    for (PetscInt k = 1; k <= sdim; ++k) {
      b[k] = 0.5 * (pts[i * sdim + k - 1] + 1.0);
      b[0] -= b[k];
    }
    rule->w[i] = wts[i] / sum;
  }
  PetscCall(PetscQuadratureDestroy(&q));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The faces of the scene's boundary conditions: ESTIMATE_FACE_CONTACT on Gamma_C, the index of the face set's
   condition, or ESTIMATE_FACE_FREE (traction-free, or loaded by the exact solution of a scene with weak data). */
static PetscErrorCode ClassifyFaces(EstimateWork *w)
{
  const BoundarySet *bcs = &w->scene->bcs;
  DMLabel            label;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc1(w->fEnd - w->fStart, &w->face_kind));
  for (PetscInt f = w->fStart; f < w->fEnd; ++f) w->face_kind[f - w->fStart] = ESTIMATE_FACE_FREE;
  PetscCall(DMGetLabel(w->dm, "Face Sets", &label));
  if (!label) PetscFunctionReturn(PETSC_SUCCESS);
  for (PetscInt i = 0; i < bcs->n + bcs->ncontact; ++i) {
    const PetscInt  id   = i < bcs->n ? bcs->bc[i].id : bcs->contact_ids[i - bcs->n];
    const PetscInt  kind = i < bcs->n ? i : ESTIMATE_FACE_CONTACT;
    IS              is;
    PetscInt        n;
    const PetscInt *pts;

    PetscCall(DMLabelGetStratumIS(label, id, &is));
    if (!is) continue;
    PetscCall(ISGetLocalSize(is, &n));
    PetscCall(ISGetIndices(is, &pts));
    for (PetscInt k = 0; k < n; ++k)
      if (pts[k] >= w->fStart && pts[k] < w->fEnd) w->face_kind[pts[k] - w->fStart] = kind;
    PetscCall(ISRestoreIndices(is, &pts));
    PetscCall(ISDestroy(&is));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The estimate of u on dm into *est; -estimate is the caller's question (its callers call it where it is asked for). */
PetscErrorCode EstimateCompute(DM dm, const EstimateRun *run, Vec u, ErrorEstimate *est)
{
  MPI_Comm       comm = PetscObjectComm((PetscObject)dm);
  EstimateWork   w;
  PetscBool      ok;
  PetscDS        ds;
  DM             cdm;
  Vec            loc_u, loc_p = NULL, coords;
  PetscReal      sums[ESTIMATE_NUM_PARTS], gsums[ESTIMATE_NUM_PARTS], total = 0.0;
  PetscLogDouble t0, t1;

  PetscFunctionBeginUser;
  PetscCall(PetscTime(&t0));
  PetscCall(EstimateReset(est));
  PetscCall(Supported(dm, run->degree, &ok, est->unavailable, sizeof(est->unavailable)));
  if (!ok) PetscFunctionReturn(PETSC_SUCCESS);

  PetscCall(PetscMemzero(&w, sizeof(w)));
  w.dm      = dm;
  w.scene   = run->scene;
  w.mat     = run->mat;
  w.verify  = run->verify;
  w.contact = run->contact;
  PetscCall(DMGetDimension(dm, &w.dim));
  PetscCall(DMPlexGetHeightStratum(dm, 0, &w.cStart, &w.cEnd));
  PetscCall(DMPlexGetHeightStratum(dm, 1, &w.fStart, &w.fEnd));
  PetscCall(MeshClosureCreate(dm, &w.mc));
  PetscCall(DMGetLocalSection(dm, &w.lsec));
  PetscCall(DMGetCoordinateDM(dm, &cdm));
  PetscCall(DMGetLocalSection(cdm, &w.csec));
  PetscCall(DMGetCoordinatesLocal(dm, &coords));
  PetscCall(VecGetArrayRead(coords, &w.xc));
  PetscCall(DMGetLocalVector(dm, &loc_u));
  PetscCall(VecCopy(run->loc_bc, loc_u)); /* the Dirichlet values, inserted once by ProblemSetUp() */
  PetscCall(DMGlobalToLocal(dm, u, INSERT_VALUES, loc_u));
  PetscCall(VecGetArrayRead(loc_u, &w.lu));
  PetscCall(ContactGetPressureForm(run->contact, &w.pressure));
  if (w.pressure.nodal) { /* the nodal force over the lumped area */
    PetscCall(DMGetLocalVector(dm, &loc_p));
    PetscCall(ErrorNormsPressureVector(dm, run->contact, loc_p));
    PetscCall(VecGetArrayRead(loc_p, &w.lp));
  }
  PetscCall(DMGetDS(dm, &ds));
  PetscCall(PetscDSGetConstants(ds, &w.nconstants, &w.constants));
  w.m_normal = run->mat->lambda + 2.0 * run->mat->mu;
  w.m_shear  = 2.0 * run->mat->mu;
  PetscCall(RuleCreate(w.dim, 2, &w.cell_rule));
  PetscCall(RuleCreate(w.dim - 1, 3, &w.face_rule));
  PetscCall(PetscCalloc1((w.cEnd - w.cStart) * ESTIMATE_NUM_PARTS, &w.eta2));
  PetscCall(PetscMalloc1(w.cEnd - w.cStart, &w.volume));
  PetscCall(ClassifyFaces(&w));

  PetscCall(EstimateResidualTerms(&w));
  PetscCall(EstimatePenaltyTerm(&w));

  for (PetscInt k = 0; k < ESTIMATE_NUM_PARTS; ++k) sums[k] = 0.0;
  est->ncells = w.cEnd - w.cStart;
  PetscCall(PetscMalloc2(est->ncells, &est->cell, est->ncells, &est->density));
  for (PetscInt c = 0; c < est->ncells; ++c) {
    PetscReal s = 0.0;

    for (PetscInt k = 0; k < ESTIMATE_NUM_PARTS; ++k) {
      sums[k] += w.eta2[c * ESTIMATE_NUM_PARTS + k];
      s += w.eta2[c * ESTIMATE_NUM_PARTS + k];
    }
    est->cell[c]    = PetscSqrtReal(s);
    est->density[c] = PetscSqrtReal(s / w.volume[c]);
  }
  PetscCall(MPIU_Allreduce(sums, gsums, ESTIMATE_NUM_PARTS, MPIU_REAL, MPIU_SUM, comm));
  for (PetscInt k = 0; k < ESTIMATE_NUM_PARTS; ++k) {
    est->part[k] = PetscSqrtReal(gsums[k]);
    total += gsums[k];
  }
  est->total = PetscSqrtReal(total);
  PetscCall(MPIU_Allreduce(&w.norm2, &est->norm, 1, MPIU_REAL, MPIU_SUM, comm));
  est->norm     = PetscSqrtReal(est->norm);
  est->computed = PETSC_TRUE;

  PetscCall(PetscFree(w.face_kind));
  PetscCall(PetscFree(w.eta2));
  PetscCall(PetscFree(w.volume));
  PetscCall(PetscFree2(w.cell_rule.bary, w.cell_rule.w));
  PetscCall(PetscFree2(w.face_rule.bary, w.face_rule.w));
  if (loc_p) {
    PetscCall(VecRestoreArrayRead(loc_p, &w.lp));
    PetscCall(DMRestoreLocalVector(dm, &loc_p));
  }
  PetscCall(VecRestoreArrayRead(loc_u, &w.lu));
  PetscCall(DMRestoreLocalVector(dm, &loc_u));
  PetscCall(VecRestoreArrayRead(coords, &w.xc));
  PetscCall(MeshClosureDestroy(&w.mc));
  PetscCall(PetscTime(&t1));
  est->time = t1 - t0;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The summary's line: the total and its parts, and the effectivity where the exact error is known. */
PetscErrorCode EstimateView(MPI_Comm comm, const ErrorEstimate *est, const ErrorNorms *exact)
{
  PetscFunctionBeginUser;
  if (!est->computed) {
    if (est->unavailable[0]) PetscCall(PetscPrintf(comm, "  error estimate: none (%s)\n", est->unavailable));
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  PetscCall(PetscPrintf(comm, "  error estimate (energy norm): %.4e =", (double)est->total));
  for (PetscInt k = 0; k < ESTIMATE_NUM_PARTS; ++k) PetscCall(PetscPrintf(comm, "%s %s %.2e", k ? "," : "", EstimateParts[k], (double)est->part[k]));
  if (!PetscIsNanReal(exact->energy) && exact->energy > 0.0)
    PetscCall(PetscPrintf(comm, "; effectivity %.3f against the exact error %.4e", (double)(est->total / exact->energy), (double)exact->energy));
  PetscCall(PetscPrintf(comm, "\n"));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The estimate's part of /run: its total and its parts (estimate_PART, the parts of include/signorini.h) and its time,
   or why the run has none (estimate_unavailable). */
PetscErrorCode EstimateWrite(const ErrorEstimate *est, PetscViewer v)
{
  PetscFunctionBeginUser;
  if (est->computed) {
    PetscCall(RunAttrReal(v, est->total, "estimate_total"));
    for (PetscInt k = 0; k < ESTIMATE_NUM_PARTS; ++k) PetscCall(RunAttrReal(v, est->part[k], "estimate_%s", EstimateParts[k]));
    PetscCall(RunAttrReal(v, est->time, "time_estimate"));
  } else if (est->unavailable[0])
    PetscCall(RunAttrString(v, est->unavailable, "estimate_unavailable"));
  PetscFunctionReturn(PETSC_SUCCESS);
}

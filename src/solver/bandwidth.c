/* -perf_bandwidth: how far the linear algebra of the run is from the memory bandwidth of the machine, measured after the
   solve in the same process: a STREAM-like triad (w = x + s y on vectors far larger than the caches), a MatMult with
   the final Jacobian, and one application of its preconditioner (the V-cycle of GAMG), each the best of several repeats.
   Bytes (summed over ranks, divided by the slowest rank's time):
   - triad: 3 x 8 B per entry (STREAM's convention: two reads and a write);
   - MatMult of an AIJ matrix with nz entries and m rows: 12 nz + 4 m (values, column indices, row starts) + 8 (m + n)
     (the vectors read and written);
   - V-cycle (a PCMG such as GAMG, one smoother per level for pre- and post-smoothing): on each level but the coarsest,
     the smoother's matrix passes (its iterations twice, one MatMult each, and one for the residual) times the level matrix's bytes, plus one pass
     of the interpolation P for the prolongation and one for the restriction; the coarsest level's direct solve and the
     smoother's vector operations are not counted, so the V-cycle figure is a lower bound of its traffic. */
#include "solver.h"
#include "app.h"

#define BANDWIDTH_TRIAD_SIZE (1 << 23) /* entries per rank: 64 MB per vector */
#define BANDWIDTH_REPEATS 10

PetscErrorCode BandwidthGetOptions(MPI_Comm comm, PetscBool *measure)
{
  PetscFunctionBeginUser;
  PetscOptionsBegin(comm, NULL, "Memory bandwidth of the linear algebra", "Signorini");
  *measure = PETSC_FALSE;
  PetscCall(PetscOptionsBool("-perf_bandwidth", "After the solve, measure the bandwidth of a triad, of MatMult and of the preconditioner", NULL,
                             *measure, measure, NULL));
  PetscOptionsEnd();
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The bytes a MatMult with A reads and writes (the accounting above). */
static PetscErrorCode MatMultBytes(Mat A, PetscReal *bytes)
{
  MatInfo  info;
  PetscInt m, n;

  PetscFunctionBeginUser;
  PetscCall(MatGetInfo(A, MAT_GLOBAL_SUM, &info));
  PetscCall(MatGetSize(A, &m, &n));
  *bytes = 12.0 * info.nz_used + 4.0 * m + 8.0 * (m + n);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The smallest time over ranks' maxima of BANDWIDTH_REPEATS calls of op (the best repeat, as STREAM reports). */
typedef PetscErrorCode (*BandwidthOp)(void *);

static PetscErrorCode BestTime(MPI_Comm comm, BandwidthOp op, void *ctx, PetscReal *best)
{
  PetscFunctionBeginUser;
  *best = PETSC_MAX_REAL;
  PetscCall(op(ctx)); /* warm up */
  for (PetscInt r = 0; r < BANDWIDTH_REPEATS; ++r) {
    PetscLogDouble t0, t1;
    PetscReal      t, tmax;

    PetscCallMPI(MPI_Barrier(comm));
    PetscCall(PetscTime(&t0));
    PetscCall(op(ctx));
    PetscCall(PetscTime(&t1));
    t = (PetscReal)(t1 - t0);
    PetscCall(MPIU_Allreduce(&t, &tmax, 1, MPIU_REAL, MPIU_MAX, comm));
    *best = PetscMin(*best, tmax);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

typedef struct {
  Vec w, x, y;
  Mat A;
  PC  pc;
} BandwidthCtx;

static PetscErrorCode OpTriad(void *ctx)
{
  BandwidthCtx *c = (BandwidthCtx *)ctx;

  PetscFunctionBeginUser;
  PetscCall(VecWAXPY(c->w, 3.0, c->x, c->y));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode OpMatMult(void *ctx)
{
  BandwidthCtx *c = (BandwidthCtx *)ctx;

  PetscFunctionBeginUser;
  PetscCall(MatMult(c->A, c->x, c->y));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode OpPCApply(void *ctx)
{
  BandwidthCtx *c = (BandwidthCtx *)ctx;

  PetscFunctionBeginUser;
  PetscCall(PCApply(c->pc, c->x, c->y));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The V-cycle's bytes (the accounting above), or -1 if the preconditioner is not a PCMG. */
static PetscErrorCode VCycleBytes(PC pc, PetscReal *bytes)
{
  PetscBool is_mg;
  PetscInt  levels;

  PetscFunctionBeginUser;
  *bytes = -1.0;
  PetscCall(PetscObjectTypeCompareAny((PetscObject)pc, &is_mg, PCMG, PCGAMG, ""));
  if (!is_mg) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PCMGGetLevels(pc, &levels));
  *bytes = 0.0;
  for (PetscInt l = 1; l < levels; ++l) { /* level 0 is the coarsest */
    KSP       smoother;
    Mat       A, P;
    PetscInt  its;
    PetscReal a, p;

    /* the one smoother of the level, pre and post (PCMGGetSmootherUp would split it into two and spoil the set-up) */
    PetscCall(PCMGGetSmoother(pc, l, &smoother));
    PetscCall(KSPGetTolerances(smoother, NULL, NULL, NULL, &its));
    PetscCall(KSPGetOperators(smoother, &A, NULL));
    PetscCall(PCMGGetInterpolation(pc, l, &P));
    PetscCall(MatMultBytes(A, &a));
    PetscCall(MatMultBytes(P, &p));
    *bytes += (2 * its + 1) * a + 2.0 * p;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* -perf_bandwidth (measure): the bandwidths with the final Jacobian of snes and its preconditioner, into b. */
PetscErrorCode BandwidthMeasure(SNES snes, PetscBool measure, Bandwidth *b)
{
  MPI_Comm     comm = PetscObjectComm((PetscObject)snes);
  BandwidthCtx c;
  KSP          ksp;
  PetscMPIInt  size;
  PetscReal    t, bytes;

  PetscFunctionBeginUser;
  if (!measure) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCallMPI(MPI_Comm_size(comm, &size));
  b->measured = PETSC_TRUE;
  /* the triad */
  PetscCall(VecCreateMPI(comm, BANDWIDTH_TRIAD_SIZE, PETSC_DETERMINE, &c.x));
  PetscCall(VecDuplicate(c.x, &c.y));
  PetscCall(VecDuplicate(c.x, &c.w));
  PetscCall(VecSet(c.x, 1.0));
  PetscCall(VecSet(c.y, 2.0));
  PetscCall(VecSet(c.w, 0.0));
  PetscCall(BestTime(comm, OpTriad, &c, &t));
  b->triad_gbs = 3.0 * 8.0 * BANDWIDTH_TRIAD_SIZE * size / t / 1e9;
  PetscCall(VecDestroy(&c.x));
  PetscCall(VecDestroy(&c.y));
  PetscCall(VecDestroy(&c.w));
  /* MatMult with the final Jacobian, and the preconditioner built for it */
  PetscCall(SNESGetKSP(snes, &ksp));
  PetscCall(KSPGetOperators(ksp, NULL, &c.A));
  PetscCall(KSPGetPC(ksp, &c.pc));
  PetscCall(MatCreateVecs(c.A, &c.x, &c.y));
  PetscCall(VecSetRandom(c.x, NULL));
  PetscCall(BestTime(comm, OpMatMult, &c, &t));
  PetscCall(MatMultBytes(c.A, &bytes));
  b->matmult_gbs = bytes / t / 1e9;
  b->matmult_s   = t;
  PetscCall(VCycleBytes(c.pc, &bytes));
  b->vcycle_gbs = b->vcycle_s = PETSC_NAN;
  if (bytes > 0.0) {
    PetscCall(BestTime(comm, OpPCApply, &c, &t));
    b->vcycle_gbs = bytes / t / 1e9;
    b->vcycle_s   = t;
  }
  PetscCall(VecDestroy(&c.x));
  PetscCall(VecDestroy(&c.y));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The summary's line of -perf_bandwidth: each bandwidth and its part of the triad's, with the times. */
PetscErrorCode BandwidthView(MPI_Comm comm, const Bandwidth *b)
{
  PetscFunctionBeginUser;
  if (!b->measured) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscPrintf(comm, "  bandwidth: triad %.2f GB/s, MatMult %.2f GB/s (%.2f of it, %.2f ms), V-cycle %.2f GB/s (%.2f of it, %.2f ms)\n",
                        (double)b->triad_gbs, (double)b->matmult_gbs, (double)(b->matmult_gbs / b->triad_gbs), (double)(1e3 * b->matmult_s),
                        (double)b->vcycle_gbs, (double)(b->vcycle_gbs / b->triad_gbs), (double)(1e3 * b->vcycle_s)));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* -perf_bandwidth's part of /run: the bandwidths and the times they come from (nothing without it). */
PetscErrorCode BandwidthWrite(const Bandwidth *b, PetscViewer v)
{
  PetscFunctionBeginUser;
  if (!b->measured) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(RunAttrReal(v, b->triad_gbs, "bandwidth_triad_gbs"));
  PetscCall(RunAttrReal(v, b->matmult_gbs, "bandwidth_matmult_gbs"));
  PetscCall(RunAttrReal(v, b->vcycle_gbs, "bandwidth_vcycle_gbs"));
  PetscCall(RunAttrReal(v, b->matmult_s, "time_matmult"));
  PetscCall(RunAttrReal(v, b->vcycle_s, "time_vcycle"));
  PetscFunctionReturn(PETSC_SUCCESS);
}

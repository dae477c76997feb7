/* The a posteriori estimate of the error of a run (src/estimate/): a residual-type estimator of the energy-norm error
   ||u - u_h||_a, with one indicator per cell, split into the parts of EstimatePart (include/signorini.h). Read only:
   it reads the solution and the contact after the solve and writes RunRecord.estimate. */
#pragma once
#include "signorini.h"
#include "mesh.h"

/* estimate.c */
PetscErrorCode EstimateGetOptions(MPI_Comm comm, RunOptions *opt);
PetscErrorCode EstimateCheckSupported(DM dm, const AppCtx *user);
PetscErrorCode EstimateReset(ErrorEstimate *est);
PetscErrorCode EstimateCompute(DM dm, AppCtx *user, Vec u);
PetscErrorCode EstimateView(MPI_Comm comm, const ErrorEstimate *est, const ErrorNorms *exact);

/* marking.c: the cells an adaptive refinement refines (Doerfler's bulk criterion) */
PetscErrorCode EstimateMark(DM dm, const ErrorEstimate *est, PetscReal theta, DMLabel *marked, PetscInt *nmarked);
/* cycle_bars.c: the bars of -accuracy's quantities on the adaptive cycles */
#define CYCLE_EPS_RATIO 10.0 /* the quantities' penalty parts on a cycle: their values at eps / CYCLE_EPS_RATIO (src/solver/adapt.c) */
PetscErrorCode CycleBarsCompute(AppCtx *user, PetscInt dim, PetscInt last);
PetscReal      CycleBarsPenaltyPart(const CycleRecord *c, PetscInt k);
PetscErrorCode EstimateMarkUnseenContact(DM dm, AppCtx *user, Vec u, DMLabel *marked, PetscInt *nunseen, PetscReal *force);
PetscErrorCode EstimateMarkContactEdge(DM dm, AppCtx *user, Vec u, DMLabel *marked, PetscInt *nmarked);

/* bars.c: -bars, the error bars of the quantities users read */
PetscErrorCode BarsCheck(MPI_Comm comm, const AppCtx *user);
PetscErrorCode BarsReset(ErrorBars *b);
PetscErrorCode BarsRecordPressure(DM dm, AppCtx *user, const PetscReal p_eps[], const PetscReal p_second[]);
/* the recorded 2h pressure carried to a remeshed level (-bars with -adapt_model): made on dm, with a local vector
   of its displacement's layout, then applied on the new mesh fine, with a local vector of its layout */
PetscErrorCode BarsPressureTransferCreate(DM dm, AppCtx *user, Vec loc, MeshTransfer *tr);
PetscErrorCode BarsPressureTransferApply(DM fine, AppCtx *user, Vec fine_loc, MeshTransfer *tr);
PetscErrorCode BarsCompute(DM dm, AppCtx *user);
PetscErrorCode BarsView(MPI_Comm comm, const ErrorBars *b);

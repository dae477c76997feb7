/* The a posteriori estimate of the error of a run (src/estimate/): a residual-type estimator of the energy-norm error
   ||u - u_h||_a, with one indicator per cell, split into the parts of EstimatePart (include/signorini.h). Read only:
   it reads the solution and the contact after the solve and writes the ErrorEstimate its caller gives. */
#pragma once
#include "signorini.h"
#include "mesh.h"

/* What the estimate reads of the run, read only: its data and the solution's discretization (the caller's pieces of it). */
typedef struct {
  const Scene         *scene;   /* the loads, the boundary conditions and Gamma_C, the obstacle, a weak-data scene's G */
  const Material      *mat;     /* the stress of u_h, and the moduli the tractions' squares are divided by */
  const VerifyOptions *verify;  /* the accurate rule of a weak-data scene's load */
  Contact              contact; /* how the pressure follows from u_h, the penalty's eps, the contact set */
  PetscInt             degree;  /* of the displacement: the estimator is P1's */
  Vec                  loc_bc;  /* the Dirichlet values, a local vector of the mesh */
} EstimateRun;

/* estimate.c */
PetscErrorCode EstimateGetOptions(MPI_Comm comm, RunOptions *opt);
/* -estimate given (estimate and estimate_given) on a discretization the estimator does not cover: refused */
PetscErrorCode EstimateCheckSupported(DM dm, PetscBool estimate, PetscBool estimate_given, PetscInt degree);
PetscErrorCode EstimateReset(ErrorEstimate *est);
/* the estimate of the solution u on dm into *est (reset first; why not, if the discretization is not P1 simplices) */
PetscErrorCode EstimateCompute(DM dm, const EstimateRun *run, Vec u, ErrorEstimate *est);
PetscErrorCode EstimateView(MPI_Comm comm, const ErrorEstimate *est, const ErrorNorms *exact);

/* marking.c: the cells an adaptive refinement refines (Doerfler's bulk criterion) */
PetscErrorCode EstimateMark(DM dm, const ErrorEstimate *est, PetscReal theta, DMLabel *marked, PetscInt *nmarked);
/* cycle_bars.c: the bars of -accuracy's quantities on the adaptive cycles */
#define CYCLE_EPS_RATIO 10.0 /* the quantities' penalty parts on a cycle: their values at eps / CYCLE_EPS_RATIO (src/drivers/adapt.c) */
/* the values and bars of cycles[last], from the cycles before it */
PetscErrorCode CycleBarsCompute(CycleRecord cycles[], PetscInt dim, PetscInt last);
PetscReal      CycleBarsPenaltyPart(const CycleRecord *c, PetscInt k);
/* the cells around the contact set's nodes the rule does not see */
PetscErrorCode EstimateMarkUnseenContact(DM dm, Contact contact, Vec u, DMLabel *marked, PetscInt *nunseen, PetscReal *force);
/* the cells of the faces faces[0..n) of Gamma_C that the contact zone's edge crosses (PostprocessContactEdgeFaces()) */
PetscErrorCode EstimateMarkContactEdge(DM dm, PetscInt n, const PetscInt faces[], DMLabel *marked, PetscInt *nmarked);

/* bars.c: -bars, the error bars of the quantities users read */
/* -bars (bars) with fewer than two nested meshes below the final one (nlevels) or several eps: refused */
PetscErrorCode BarsCheck(MPI_Comm comm, PetscBool bars, PetscInt nlevels, Contact contact);
PetscErrorCode BarsReset(ErrorBars *b);
/* the 2h level's nodal pressure p_eps[] and that at the second eps p_second[] (NULL: none), kept in *b at the vertices */
PetscErrorCode BarsRecordPressure(DM dm, Contact contact, const PetscReal p_eps[], const PetscReal p_second[], ErrorBars *b);
/* the recorded 2h pressure carried to a remeshed level (-bars with -adapt_model): made on dm, with a local vector
   of its displacement's layout, then applied on the new mesh fine, with a local vector of its layout */
PetscErrorCode BarsPressureTransferCreate(DM dm, const ErrorBars *b, Vec loc, MeshTransfer *tr);
PetscErrorCode BarsPressureTransferApply(DM fine, ErrorBars *b, Vec fine_loc, MeshTransfer *tr);
/* the bars of the final mesh's quantities q (bcs: its supports' reactions; converged: the run's solves) and the
   pressure's band at the contact set's nodes, into *b, from the levels b recorded */
PetscErrorCode BarsCompute(DM dm, const BoundarySet *bcs, Contact contact, const Quantities *q, PetscBool converged, ErrorBars *b);
PetscErrorCode BarsView(MPI_Comm comm, const ErrorBars *b);
PetscErrorCode EstimateWrite(const ErrorEstimate *est, PetscViewer v); /* its part of /run */
PetscErrorCode BarsWrite(const ErrorBars *b, PetscViewer v);           /* -bars' part of /run */

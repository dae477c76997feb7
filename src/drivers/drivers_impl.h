/* The drivers' own header (src/drivers/): the object each driver type fills (its operations and data), the types'
   constructors, which drivers.c registers, and what one driver uses of another. */
#pragma once
#include "drivers.h"

typedef struct _n_Driver *Driver;

/* A driver's operations: solve moves the run on (it may change the mesh, the SNES and the solution); view and write,
   where not NULL, show its results; fields, where not NULL, gives the state fields of its steps, a time series in the
   output (include/io.h); destroy frees its data. */
typedef struct {
  PetscErrorCode (*solve)(Driver d, AppCtx *user, DM *dm, SNES *snes, Vec *u);
  PetscErrorCode (*view)(Driver d, MPI_Comm comm, const DriverReport *r);
  PetscErrorCode (*write)(Driver d, MPI_Comm comm, const DriverReport *r, PetscViewer v);
  PetscErrorCode (*fields)(Driver d, PetscInt *nsteps, Vec const **fields);
  PetscErrorCode (*destroy)(Driver d);
} DriverOps;
struct _n_Driver {
  char         name[32];
  DriverOps    ops;
  void        *data;       /* the driver's own state and results */
  OutputWriter checkpoint; /* writes the run's output as it stands, for a driver that keeps what it finished */
};
typedef PetscErrorCode (*DriverCreateFn)(Driver d);
PetscErrorCode DriverCreate_GridSequence(Driver d);
PetscErrorCode DriverCreate_Adapt(Driver d);
PetscErrorCode DriverCreate_EpsSweep(Driver d);
PetscErrorCode DriverCreate_PenetrationTol(Driver d);
PetscErrorCode DriverCreate_LoadPath(Driver d);

/* grid_sequence.c: a mesh refined (where marked, or everywhere) or remeshed from the Gmsh model, with the solution
   carried to it and solved there: the nested iteration's levels and the adaptive cycles' meshes */
PetscErrorCode GridSequenceRefine(DM *dm, AppCtx *user, SNES *snes, Vec *u, DMLabel marked);
PetscErrorCode GridSequenceRemesh(DM *dm, AppCtx *user, SNES *snes, Vec *u, DMLabel marked, PetscReal unmarked);
/* eps_sweep.c: the tangent of the solution path in eps, the sweep's and the cycles' second eps */
PetscErrorCode EpsSweepTangent(SNES snes, DM dm, Contact ct, Vec u, Vec dir, PetscInt *ksp_its_total, PetscBool *ok);
/* penetration_tol.c: the continuation to -contact_penetration_tol from the last solution, on the final mesh and at each
   step of a load path */
PetscErrorCode PenetrationTolReach(DM dm, AppCtx *user, SNES snes, Vec u);

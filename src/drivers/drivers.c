/* The drivers' registry and the run's flow. A driver type is registered by name with its constructor, as PETSc registers
   its KSP types; DriversCreate() makes one driver of each type named in DRIVER_FLOW, in that order, and DriversSolve()
   runs them in turn on the run's last solution. The order is the composition: each driver solves on from where the
   drivers before it left the run, so that the adaptive cycles refine the grid sequence's mesh, and the eps sweep, the
   penetration tolerance and the load path all work on the final mesh. */
#include "drivers_impl.h"

static PetscFunctionList driver_list = NULL;

/* The run's flow: the first solve (with its nested iteration), the adaptive cycles, then on the final mesh the eps
   sweep, the continuation to a penetration tolerance and the load path (whose later steps each reach the penetration
   tolerance too, PenetrationTolReach()). */
static const char *const DRIVER_FLOW[] = {"grid_sequence", "adapt", "eps_sweep", "penetration_tol", "load_path"};
#define DRIVER_FLOW_N ((PetscInt)(sizeof(DRIVER_FLOW) / sizeof(DRIVER_FLOW[0])))

struct _n_Drivers {
  PetscInt n;
  Driver   d[DRIVER_FLOW_N];
};

PetscErrorCode DriverRegisterAll(void)
{
  PetscFunctionBeginUser;
  if (driver_list) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscFunctionListAdd(&driver_list, "grid_sequence", DriverCreate_GridSequence));
  PetscCall(PetscFunctionListAdd(&driver_list, "adapt", DriverCreate_Adapt));
  PetscCall(PetscFunctionListAdd(&driver_list, "eps_sweep", DriverCreate_EpsSweep));
  PetscCall(PetscFunctionListAdd(&driver_list, "penetration_tol", DriverCreate_PenetrationTol));
  PetscCall(PetscFunctionListAdd(&driver_list, "load_path", DriverCreate_LoadPath));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode DriverFinalize(void)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFunctionListDestroy(&driver_list));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The drivers of the run's flow (registered by DriverRegisterAll() first); checkpoint writes the run's output as it stands (the adaptive cycles write each
   finished cycle, so that an interrupted run keeps them). */
PetscErrorCode DriversCreate(OutputWriter checkpoint, Drivers *list)
{
  PetscFunctionBeginUser;
  PetscCall(PetscNew(list));
  for (PetscInt k = 0; k < DRIVER_FLOW_N; ++k) {
    DriverCreateFn create;
    Driver         d;

    PetscCall(PetscFunctionListFind(driver_list, DRIVER_FLOW[k], &create));
    PetscCheck(create, PETSC_COMM_SELF, PETSC_ERR_PLIB, "No driver type %s is registered", DRIVER_FLOW[k]);
    PetscCall(PetscNew(&d));
    PetscCall(PetscStrncpy(d->name, DRIVER_FLOW[k], sizeof(d->name)));
    d->checkpoint = checkpoint;
    PetscCall((*create)(d));
    (*list)->d[(*list)->n++] = d;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Each driver in turn, from the solution the last one left: u on the mesh dm, with its SNES. */
PetscErrorCode DriversSolve(Drivers list, AppCtx *user, DM *dm, SNES *snes, Vec *u)
{
  PetscFunctionBeginUser;
  for (PetscInt k = 0; k < list->n; ++k) PetscCall((*list->d[k]->ops.solve)(list->d[k], user, dm, snes, u));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The drivers' results in the summary, in the order of the flow. */
PetscErrorCode DriversView(Drivers list, MPI_Comm comm, const DriverReport *r)
{
  PetscFunctionBeginUser;
  for (PetscInt k = 0; k < list->n; ++k)
    if (list->d[k]->ops.view) PetscCall((*list->d[k]->ops.view)(list->d[k], comm, r));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The drivers' parts of /run and their tables (/steps, /cycles) in the output. */
PetscErrorCode DriversWrite(Drivers list, MPI_Comm comm, const DriverReport *r, PetscViewer v)
{
  PetscFunctionBeginUser;
  for (PetscInt k = 0; k < list->n; ++k)
    if (list->d[k]->ops.write) PetscCall((*list->d[k]->ops.write)(list->d[k], comm, r, v));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The state fields of a driver's steps, the output's time series (none: nsteps = 0). One driver at most has steps. */
PetscErrorCode DriversGetStepFields(Drivers list, PetscInt *nsteps, Vec const **fields)
{
  PetscFunctionBeginUser;
  *nsteps = 0;
  *fields = NULL;
  for (PetscInt k = 0; k < list->n && !*nsteps; ++k)
    if (list->d[k]->ops.fields) PetscCall((*list->d[k]->ops.fields)(list->d[k], nsteps, fields));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode DriversDestroy(Drivers *list)
{
  PetscFunctionBeginUser;
  if (!*list) PetscFunctionReturn(PETSC_SUCCESS);
  for (PetscInt k = 0; k < (*list)->n; ++k) {
    if ((*list)->d[k]->ops.destroy) PetscCall((*(*list)->d[k]->ops.destroy)((*list)->d[k]));
    PetscCall(PetscFree((*list)->d[k]));
  }
  PetscCall(PetscFree(*list));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* -penalty_eps0_sweep a,b,c,...: the penalty problems for eps = eps0 h^power / M with eps0 = a, b, c, ... solved in
   turn on the final mesh, each from the solution for the previous value (the first is the run's main solve). The
   bulk matrix, the load and the solver objects are shared; the output holds the last solution, and /solves one row
   per value. A failed value ends the sweep. */
#include "physics.h"
#include "solver.h"

PetscErrorCode EpsSweepSolve(DM dm, AppCtx *user, SNES snes, Vec u)
{
  PetscFunctionBeginUser;
  for (PetscInt k = 1; k < user->opt.contact.n_sweep && user->rec.stats.converged; ++k) {
    user->opt.contact.eps0 = user->opt.contact.eps0_sweep[k];
    PetscCall(ContactComputeEps(user));
    PetscCall(ElasticityUpdateConstants(dm, user));
    PetscCall(SolverSolve(snes, user, u, SOLVER_START_NEARBY_EPS));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

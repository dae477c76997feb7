/* Active set of Gamma_C and the per-Newton-step contact monitor (-contact_monitor). */
#include "contact.h"
#include "solver_impl.h"

/* Semismooth Newton on the penalty problem can cycle between active sets. When the active set of this step is one
   already met two or more steps back (and not the previous one) with no less than half its residual, the cycle is
   reported and, with -contact_cycle_damping, the next Newton step is damped by half (SNESLineSearchSetDamping) to leave
   the cycle; the steps after it are full again (a damping kept on would lose the finite termination of Newton). */
static PetscErrorCode DetectActiveSetCycle(SNES snes, SolverCtx sc, PetscInt it, PetscReal fnorm, Vec X)
{
  SNESLineSearch ls;
  PetscInt64     hash;

  PetscFunctionBeginUser;
  PetscCall(SNESGetLineSearch(snes, &ls));
  PetscCall(SNESLineSearchSetDamping(ls, 1.0));
  PetscCall(ContactPenetrationHash(sc->contact, X, &hash));
  if (it >= CONTACT_HISTORY) PetscFunctionReturn(PETSC_SUCCESS);
  sc->active_history[it] = hash;
  sc->fnorm_history[it]  = fnorm;
  for (PetscInt j = it - 2; j >= 0; --j) {
    if (sc->active_history[j] != hash || sc->active_history[it - 1] == hash || fnorm < 0.5 * sc->fnorm_history[j]) continue;
    sc->stats->active_set_cycles++;
    if (sc->opt->cycle_damping) PetscCall(SNESLineSearchSetDamping(ls, 0.5));
    PetscCall(PetscPrintf(PetscObjectComm((PetscObject)snes),
                          "  active-set cycle: Newton step %" PetscInt_FMT " is back at the active set of step %" PetscInt_FMT
                          " (|F| %g, then %g)%s\n",
                          it, j, (double)sc->fnorm_history[j], (double)fnorm,
                          sc->opt->cycle_damping ? "; the next step is damped by 1/2" : "; not damped (-contact_cycle_damping 0)"));
    break;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The SNES iterates on x~ = u/U with the residual F/U (solver.c): the monitor reports u and |F| in the user's units. */
PetscErrorCode ContactMonitor(SNES snes, PetscInt it, PetscReal fnorm_scaled, void *ctx)
{
  SolverCtx       sc    = (SolverCtx)ctx;
  const PetscReal fnorm = fnorm_scaled * sc->snes_scale;
  Vec             X, Xs;
  PetscInt        active, entered, left;

  PetscFunctionBeginUser;
  sc->stats->residual_norm = fnorm;
  PetscCall(SNESGetSolution(snes, &Xs));
  PetscCall(SolverIterateDisplacement(sc, Xs, &X));
  {
    const ContactSolverDefaults *defaults;

    PetscCall(ContactGetSolverDefaults(sc->contact, &defaults));
    if (defaults->active_set_cycles) PetscCall(DetectActiveSetCycle(snes, sc, it, fnorm, X));
  }
  if (!sc->opt->monitor) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(ContactCountActive(sc->contact, X, sc->displacement_scale, PETSC_TRUE, &active, &entered, &left));
  PetscCall(PetscPrintf(PetscObjectComm((PetscObject)snes),
                        "  %3" PetscInt_FMT " contact: |F| %12.6e  active vertices %6" PetscInt_FMT "  entered %5" PetscInt_FMT
                        "  left %5" PetscInt_FMT "\n",
                        it, (double)fnorm, active, entered, left));
  PetscFunctionReturn(PETSC_SUCCESS);
}

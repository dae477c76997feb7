/* Gmsh's library, loaded at the first call that needs it (the first remesh, MeshGmshLoad()): linked, its library and
   OpenCASCADE's added 0.22 s to the start of every run (0.44 s to 0.66 s on a 4 x 4 box), remeshing or not. */
#include <dlfcn.h>
#include "mesh_gmsh.h"

MeshGmshApi gmsh_api;

/* RTLD_DEEPBIND: Gmsh's libraries look their symbols up in their own dependencies first, not through the solver's
   whole global scope (PETSc's, MPI's and HDF5's libraries) before them. Gmsh brings 71 libraries of its own
   (OpenCASCADE, FLTK, image formats); its loading took 0.24 to 0.35 s of the Hertz cylinder's first remesh so, 0.08 to
   0.11 s with it (RTLD_LAZY alone: 0.24 to 0.27 s). It also keeps Gmsh's libraries from binding to a same-named symbol
   of the solver's. Not under AddressSanitizer, whose runtime refuses it. */
#if defined(RTLD_DEEPBIND) && !defined(__SANITIZE_ADDRESS__)
#  define GMSH_DLOPEN (RTLD_NOW | RTLD_LOCAL | RTLD_DEEPBIND)
#else
#  define GMSH_DLOPEN (RTLD_NOW | RTLD_LOCAL)
#endif

PetscErrorCode MeshGmshLoad(void)
{
  PetscFunctionBeginUser;
  if (gmsh_api.lib) PetscFunctionReturn(PETSC_SUCCESS);
  gmsh_api.lib = dlopen("libgmsh.so.4.8", GMSH_DLOPEN);
  if (!gmsh_api.lib) gmsh_api.lib = dlopen("libgmsh.so", GMSH_DLOPEN);
  PetscCheck(gmsh_api.lib, PETSC_COMM_SELF, PETSC_ERR_LIB, "Gmsh's library cannot be loaded (%s): apt-get install libgmsh4.8", dlerror());
#define GMSH_LOAD(f)                                     \
  gmsh_api.f = (__typeof__(f) *)dlsym(gmsh_api.lib, #f); \
  PetscCheck(gmsh_api.f, PETSC_COMM_SELF, PETSC_ERR_LIB, "Gmsh's library has no %s", #f);
  GMSH_FUNCTIONS(GMSH_LOAD)
  PetscFunctionReturn(PETSC_SUCCESS);
}

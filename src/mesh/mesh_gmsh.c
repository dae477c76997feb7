/* Gmsh's library, loaded at the first call that needs it (the first remesh, MeshGmshLoad()): linked, its library and
   OpenCASCADE's would load at the start of every run, remeshing or not (docs/decisions.md, "Gmsh's library"). */
#include <dlfcn.h>
#include "mesh_gmsh.h"

MeshGmshApi gmsh_api;

/* RTLD_DEEPBIND: Gmsh's libraries look their symbols up in their own dependencies first, not through the solver's
   whole global scope (PETSc's, MPI's and HDF5's libraries) before them, which makes their loading several times
   faster (docs/decisions.md, "Gmsh's library"). It also keeps Gmsh's libraries from binding to a same-named symbol
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

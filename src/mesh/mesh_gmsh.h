/* Gmsh's C API as the solver loads it (mesh_gmsh.c), for the files that call Gmsh on rank 0: the remeshing
   (mesh_remesh.c) and the mesh taken from it (mesh_gmsh_build.c). */
#pragma once
#include <gmshc.h>
#include "mesh.h"

/* The functions of Gmsh's C API the solver calls, loaded with the library (MeshGmshLoad()). */
#define GMSH_FUNCTIONS(X)                  \
  X(gmshFinalize)                          \
  X(gmshFree)                              \
  X(gmshInitialize)                        \
  X(gmshLoggerGetLastError)                \
  X(gmshModelAdd)                          \
  X(gmshModelAddPhysicalGroup)             \
  X(gmshModelGetBoundingBox)               \
  X(gmshModelGetClosestPoint)              \
  X(gmshModelGetDimension)                 \
  X(gmshModelGetEntities)                  \
  X(gmshModelGetEntitiesForPhysicalGroup)  \
  X(gmshModelGetPhysicalGroups)            \
  X(gmshModelGetPhysicalGroupsForEntity)   \
  X(gmshModelGetPhysicalName)              \
  X(gmshModelMeshGetElements)              \
  X(gmshModelMeshGetNodes)                 \
  X(gmshModelMeshFieldAdd)                 \
  X(gmshModelMeshFieldSetAsBackgroundMesh) \
  X(gmshModelMeshFieldSetNumber)           \
  X(gmshModelMeshGenerate)                 \
  X(gmshModelOccAddBox)                    \
  X(gmshModelOccSynchronize)               \
  X(gmshOpen)                              \
  X(gmshOptionGetNumber)                   \
  X(gmshOptionSetNumber)                   \
  X(gmshViewAdd)                           \
  X(gmshViewAddListData)                   \
  X(gmshWrite)
#define GMSH_DECLARE(f) __typeof__(f) *f;
typedef struct {
  void *lib;
  GMSH_FUNCTIONS(GMSH_DECLARE)
} MeshGmshApi;
extern MeshGmshApi gmsh_api;

PetscErrorCode MeshGmshLoad(void);
PetscErrorCode MeshSimplicesFromGmsh(PetscInt dim, MeshSimplices *s);

/* A Gmsh call's error as a PETSc error, with Gmsh's last message. */
#define GmshCall(call, what)                                                                                       \
  do {                                                                                                             \
    int ierr_gmsh = 0;                                                                                             \
    call;                                                                                                          \
    if (ierr_gmsh) {                                                                                               \
      char *msg = NULL;                                                                                            \
      int   e2  = 0;                                                                                               \
      gmsh_api.gmshLoggerGetLastError(&msg, &e2);                                                                  \
      SETERRQ(PETSC_COMM_SELF, PETSC_ERR_LIB, "Gmsh failed to %s: %s", what, msg &&msg[0] ? msg : "(no message)"); \
    }                                                                                                              \
  } while (0)

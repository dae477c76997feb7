/* Meshes: creation, size checks, face sets, refinement with interpolation, distribution (src/mesh/). */
#pragma once
#include "signorini.h"
#include <petscdmplextransform.h>

/* mesh.c, mesh_box_simplex.c */
PetscErrorCode MeshCreate(MPI_Comm comm, PetscInt later_refinements, const PetscInt coarse_requests[2], const PetscInt coarse_faces[3],
                          PetscInt coarse_min_levels, MeshBox *box, DM *dm);
PetscErrorCode MeshIndexCellTypes(DM dm);
PetscErrorCode MeshReadRemeshedFile(MPI_Comm comm, const char filename[], DM *dm);
PetscErrorCode MeshDistributeRemeshed(const char what[], DM *dm);
PetscErrorCode MeshCheckSize(MPI_Comm comm, PetscInt dim, PetscReal ncells, const char what[]);
PetscErrorCode MeshCreateSimplexBox(MPI_Comm comm, PetscInt dim, const PetscInt faces[], const PetscReal lower[], const PetscReal upper[],
                                    PetscBool distribute, PetscInt slab_rows, PetscBool petsc_interpolate, PetscBool check, DM *dm);
PetscErrorCode MeshLabelBoxFaces(DM dm, const PetscReal lower[], const PetscReal upper[]);
PetscInt       MeshBoxFaceId(PetscInt dim, PetscInt d, PetscInt s);
PetscErrorCode MeshCreateBoxLevel(DM coarse, const MeshBox *box, PetscInt level, DM *fine, PetscInt **vertex_source);
PetscErrorCode MeshBoxWrite(const MeshBox *box, PetscViewer v); /* its part of /run */
PetscErrorCode MeshGetMaxCellDiameter(DM dm, PetscReal *h);
PetscErrorCode MeshCellDiameter(DM dm, PetscInt c, PetscReal *diam);
PetscErrorCode MeshCellMeanEdge(DM dm, PetscInt c, PetscReal *mean);
PetscErrorCode MeshCellSize(DM dm, PetscInt c, PetscReal *h);
PetscErrorCode MeshGetMaxCellSize(DM dm, PetscReal diameter_max, PetscReal *h);
PetscErrorCode MeshSetCellSizes(DM dm, PetscReal hmax, PetscReal *sizes);
PetscErrorCode MeshSetContactCellSizes(DM dm, PetscInt nids, const PetscInt ids[]);
PetscErrorCode MeshCheckContactBoundary(DM dm, PetscInt contact_id);
PetscErrorCode MeshCountOwned(DM dm, PetscInt pStart, PetscInt pEnd, PetscInt *count);
PetscErrorCode MeshOwnedIndex(DM dm, PetscInt pStart, PetscInt pEnd, PetscInt **index, PetscInt *nowned);
PetscErrorCode MeshGetBoundaryFaces(DM dm, PetscInt id, PetscInt *n, PetscInt **faces);
PetscErrorCode MeshPointGlobalIndices(PetscSection lsec, PetscSection gsec, PetscInt p, PetscInt dim, PetscInt idx[]);

/* mesh_point.c */
PetscErrorCode MeshPointPosition(DM dm, PetscInt p, PetscReal x[]);
PetscErrorCode MeshFaceOutwardGeometry(DM dm, PetscInt f, PetscInt dim, PetscReal n[], PetscReal xc[], PetscReal *area);

/* mesh_interpolate.c */
/* The local vertices' global numbers, which are shared with other ranks, and whether a face (its vertices' global
   numbers) lies on the domain's boundary: what the direct build of a distributed mesh needs. */
typedef PetscBool (*MeshOnBoundary)(PetscInt n, const PetscInt gid[], void *ctx);
typedef struct {
  const PetscInt  *gid;
  const PetscBool *shared;
  MeshOnBoundary   on_boundary;
  void            *ctx;
} MeshInterface;
PetscErrorCode MeshCreateInterpolatedSimplices(MPI_Comm comm, PetscInt dim, PetscInt ncells, PetscInt nverts, const PetscInt cells[],
                                               const MeshInterface *itf, DM *dm);
PetscErrorCode MeshCreateInterpolatedSimplicesParallel(MPI_Comm comm, PetscInt dim, PetscInt ncells, PetscInt nverts_owned, PetscInt nverts_total,
                                                       const PetscInt cells[], const PetscReal coords[], MeshOnBoundary on_boundary, void *ctx,
                                                       DM *dm);
PetscErrorCode MeshCompareTopology(DM a, DM b, PetscInt *differences, PetscInt *compared);

/* mesh_closure.c: DMPlexGetTransitiveClosure() without the cell-type lookups, where each depth has one cell type */
typedef struct {
  DM             dm;
  PetscInt       dim, vstart, vend; /* the vertices */
  PetscInt       depth, start[4], end[4];
  DMPolytopeType type[4];    /* the type of every point of each depth */
  PetscBool      by_depth;   /* else DMPlexGetTransitiveClosure() */
  PetscInt       max_points; /* of a closure or star */
  PetscInt      *points, *fifo;
  PetscSection   cone_section; /* the DM's cones, read directly */
  PetscInt      *cones, *cone_ornts;
} MeshClosure;
PetscErrorCode MeshClosureCreate(DM dm, MeshClosure *mc);
PetscErrorCode MeshClosureDestroy(MeshClosure *mc);
PetscErrorCode MeshClosureGet(MeshClosure *mc, PetscInt p, PetscBool use_cone, PetscInt *n, const PetscInt **points);
PetscErrorCode MeshClosureVertices(MeshClosure *mc, PetscInt p, PetscInt max, PetscInt *nv, PetscInt verts[]);
PetscErrorCode MeshClosureCheck(DM dm, PetscInt *differences, PetscBool *by_depth);

/* mesh_check.c: what the discretization cannot handle, refused before anything is assembled */
PetscErrorCode MeshCheckFile(DM dm, const char filename[]);
PetscErrorCode MeshOrientCells(DM dm, const char what[], PetscInt *nreflected);
PetscErrorCode MeshCountInteriorFaces(DM dm, PetscInt n, const PetscInt faces[], PetscInt *ninterior);
PetscErrorCode MeshCountCurvedRidges(DM dm, PetscInt *count, PetscReal x[3]);

/* mesh_gmsh_names.c: a label per named physical group of faces (PETSc labels them by number only) */
#define MESH_MAX_NAMES 64
typedef struct {
  int  dim, tag;
  char name[64];
} MeshPhysicalName;
PetscErrorCode MeshLabelPhysicalNames(DM dm, int n, const MeshPhysicalName names[]);
PetscErrorCode MeshLabelGmshNames(DM dm, const char filename[]);

/* mesh_gmsh_build.c: the mesh Gmsh made for a remeshing, on rank 0, as PETSc's Gmsh reader numbers the file Gmsh would
   write (taken from Gmsh by MeshSimplicesFromGmsh(), src/mesh/mesh_gmsh.h), built as that reader builds it with
   interpolation */
typedef struct {
  PetscInt         dim, ncells, nverts, nfaces;
  PetscInt        *cells, *cell_set; /* [ncells][dim + 1] vertices, oriented as PETSc orients them; the first physical tag (-1: none) */
  PetscReal       *coords;           /* [nverts][dim] */
  PetscInt        *faces, *face_set; /* [nfaces][dim] vertices of the elements of dimension dim - 1; their first physical tag */
  int              nnames;
  MeshPhysicalName names[MESH_MAX_NAMES];
} MeshSimplices;
PetscErrorCode MeshSimplicesBuild(MPI_Comm comm, const MeshSimplices *s, DM *dm);
PetscErrorCode MeshSimplicesReset(MeshSimplices *s);

/* mesh_refine.c */
PetscErrorCode MeshCellVertices(DM dm, PetscInt c, PetscInt verts[], PetscInt *nv);
PetscErrorCode MeshCellReferenceCoordinates(DM dm, PetscInt c, PetscInt n, const PetscReal x[], PetscReal xi[]);
PetscErrorCode MeshRefineRegular(DM dm, PetscInt levels, DM *fine, PetscInt **parent, PetscInt **vertex_source);
PetscErrorCode MeshRefineMarked(DM dm, DMLabel marked, DM *fine, PetscInt **vertex_source);
PetscErrorCode MeshRefineSBRLookups(DMPlexTransform tr);
PetscErrorCode MeshDescendantSizes(DM dm, PetscInt levels, PetscReal power, PetscReal **sizes, PetscReal *hmax);
PetscErrorCode MeshSourceVertices(DM dm, const PetscInt vb[2], const PetscInt eb[2], PetscInt src, PetscInt verts[], PetscInt *nv);
PetscErrorCode MeshInterpolateVertexSources(DM dm, DM fine, const PetscInt vertex_source[], Vec loc, Vec *fine_loc);
PetscErrorCode MeshInterpolateVertexArrays(DM dm, DM fine, const PetscInt vertex_source[], PetscInt nc, PetscReal *const coarse[],
                                           PetscReal *fine_values[]);
PetscErrorCode MeshInterpolateFromParents(DM dm, DM fine, const PetscInt parent[], PetscInt nvec, Vec loc[], Vec fine_loc[]);

/* mesh_locate.c: the cell of a simplex mesh, given by its cells' vertices x[ncells][dim + 1][dim] (kept by the caller),
   that holds a point, and the point's barycentric coordinates in it */
typedef struct _n_MeshLocator *MeshLocator;
PetscErrorCode                 MeshLocatorCreate(PetscInt dim, PetscInt ncells, const PetscReal x[], MeshLocator *locator);
void                           MeshLocatorFind(MeshLocator locator, const PetscReal p[], PetscInt *cell, PetscReal lambda[]);
PetscErrorCode                 MeshLocatorDestroy(MeshLocator *locator);

/* mesh_transfer.c: a P1 field carried from a mesh to its remeshing (the old cells on rank 0) */
typedef struct _n_MeshTransfer *MeshTransfer;
PetscErrorCode                  MeshTransferCreate(MPI_Comm comm, PetscInt dim, PetscInt ncells, PetscReal x[], PetscReal u[], MeshTransfer *tr);
PetscErrorCode                  MeshTransferCreateFromField(DM dm, Vec loc, MeshTransfer *tr);
PetscErrorCode                  MeshTransferApply(MeshTransfer tr, DM fine, Vec fine_loc);
PetscErrorCode                  MeshTransferDestroy(MeshTransfer *tr);

/* mesh_remesh.c: the Gmsh model meshed again with a size per cell of dm (-adapt_model), or the box of the options
   (model "" and box); a field of dm goes to the new mesh by MeshTransferCreateFromField(), made before */
PetscErrorCode MeshRemesh(DM dm, const char model[], const MeshBox *box, const PetscReal size[], DM *remeshed);
/* which "Face Sets" values a face carries on some rank (present[v], v < n) */
PetscErrorCode MeshFaceSetValues(DM dm, PetscInt *n, PetscBool **present);
/* mesh_model_check.c: a model the cycles could not remesh as the mesh's body, refused before the first solve */
PetscErrorCode MeshRemeshCheckModel(DM dm, const char model[]);
/* mesh_remesh_caps.c: caps over the boundary faces of MeshRemesh()'s size view (cells of nv vertices, 4 nv doubles each) */
PetscErrorCode MeshRemeshViewCaps(PetscInt ncells, PetscInt nv, PetscInt dim, const double data[], PetscInt *ncaps, double **caps);

/* mesh_partition.c */
PetscErrorCode MeshPartitionDistribute(MeshPartitionerType type, DM *dm);
PetscErrorCode MeshPartitionGetStats(DM dm, MeshPartitionStats *stats);
PetscErrorCode MeshPartitionWrite(const MeshPartitionStats *ps, PetscViewer v); /* its part of /run */

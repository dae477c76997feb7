/* The mesh Gmsh made at a remeshing (mesh_remesh.c), taken from Gmsh's API rather than from a file, built as PETSc
   3.18's Gmsh reader (DMPlexCreateGmsh() with interpolation) builds the file Gmsh would write (MSH 4.1; where the model
   has physical groups, the elements of their entities alone, unless it sets Mesh.SaveAll):
   - the vertices: the nodes some saved element uses, in Gmsh's node order (its entities' order: points, curves,
     surfaces, volumes, each by tag), PETSc's vertexMap;
   - the cells: the saved elements of the mesh's dimension in Gmsh's element order (the entities' order), each cone
     oriented by DMPlexInvertCell() as DMPlexReorderCell() orients it (a tetrahedron's first two vertices swapped);
   - the faces and edges: DMPlexInterpolate()'s points, cones and orientations, built directly as the simplex box's are
     (MeshCreateInterpolatedSimplices()): DMPlexInterpolate() was four fifths of PETSc's reading and a tenth of a 3D
     adaptive run (docs/estimate.md, "The remeshing's own costs");
   - "Cell Sets": each cell the first physical tag of its entity; "Face Sets": the face that the vertices of a saved
     element of dimension dim - 1 join (DMPlexGetFullJoin()), the first physical tag of its entity (PETSc's default,
     without -dm_plex_gmsh_multiple_tags);
   - a label per named physical group of faces (MeshLabelPhysicalNames()), as a mesh file's $PhysicalNames give.
   Checked against PETSc's reading of the file Gmsh writes (-mesh_remeshed_petsc_read, tests/test_remesh.py): every
   /cycles value the same to the last bit. Rank 0 holds the mesh and the other ranks the empty mesh, as with PETSc's
   reader, until the distribution. */
#include "mesh.h"

PetscErrorCode MeshSimplicesBuild(MPI_Comm comm, const MeshSimplices *s, DM *dm)
{
  PetscInt    flags[2] = {s->dim, 0}, dim, cStart, vStart;
  PetscMPIInt rank;
  DMLabel     face_sets;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  for (PetscInt c = 0; c < s->ncells && !flags[1]; ++c) flags[1] = s->cell_set[c] >= 0;
  PetscCallMPI(MPI_Bcast(flags, 2, MPIU_INT, 0, comm));
  dim = flags[0];
  PetscCall(MeshCreateInterpolatedSimplices(comm, dim, rank ? 0 : s->ncells, rank ? 0 : s->nverts, s->cells, NULL, dm));
  PetscCall(DMPlexBuildCoordinatesFromCellList(*dm, dim, s->coords));
  PetscCall(DMPlexGetHeightStratum(*dm, 0, &cStart, NULL));
  PetscCall(DMPlexGetDepthStratum(*dm, 0, &vStart, NULL));
  if (flags[1]) {
    DMLabel cell_sets;

    PetscCall(DMCreateLabel(*dm, "Cell Sets"));
    PetscCall(DMGetLabel(*dm, "Cell Sets", &cell_sets));
    for (PetscInt c = 0; c < (rank ? 0 : s->ncells); ++c)
      if (s->cell_set[c] >= 0) PetscCall(DMLabelSetValue(cell_sets, cStart + c, s->cell_set[c]));
  }
  PetscCall(DMCreateLabel(*dm, "Face Sets"));
  PetscCall(DMGetLabel(*dm, "Face Sets", &face_sets));
  for (PetscInt f = 0; f < (rank ? 0 : s->nfaces); ++f) {
    PetscInt        verts[3], njoin;
    const PetscInt *join = NULL;

    if (s->face_set[f] < 0) continue;
    for (PetscInt k = 0; k < dim; ++k) verts[k] = vStart + s->faces[f * dim + k];
    PetscCall(DMPlexGetFullJoin(*dm, dim, verts, &njoin, &join));
    PetscCheck(njoin == 1, PETSC_COMM_SELF, PETSC_ERR_PLIB, "no face of the mesh Gmsh made joins the vertices of its boundary element %" PetscInt_FMT,
               f);
    PetscCall(DMLabelSetValue(face_sets, join[0], s->face_set[f]));
    PetscCall(DMPlexRestoreJoin(*dm, dim, verts, &njoin, &join));
  }
  PetscCall(MeshLabelPhysicalNames(*dm, rank ? 0 : s->nnames, s->names));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode MeshSimplicesReset(MeshSimplices *s)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFree(s->cells));
  PetscCall(PetscFree(s->cell_set));
  PetscCall(PetscFree(s->coords));
  PetscCall(PetscFree(s->faces));
  PetscCall(PetscFree(s->face_set));
  PetscCall(PetscMemzero(s, sizeof(*s)));
  PetscFunctionReturn(PETSC_SUCCESS);
}

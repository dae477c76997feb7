/* The mesh Gmsh made at a remeshing (mesh_remesh.c), taken from Gmsh's API on rank 0 (MeshSimplicesFromGmsh(), while
   Gmsh holds it) rather than from a file, and built (MeshSimplicesBuild()) as PETSc 3.18's Gmsh reader
   (DMPlexCreateGmsh() with interpolation) builds the file Gmsh would write (MSH 4.1; where the model has physical
   groups, the elements of their entities alone, unless it sets Mesh.SaveAll):
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
   - a label per named physical group of faces (MeshLabelPhysicalNames()), as a mesh file's $PhysicalNames give;
   - the coordinates to the file's 16 digits (MeshSimplicesFromGmsh()).
   Checked against PETSc's reading of the file Gmsh writes (-mesh_remeshed_petsc_read, tests/test_remesh.py): every
   /cycles value the same to the last bit. Rank 0 holds the mesh and the other ranks the empty mesh, as with PETSc's
   reader, until the distribution.
   One of PETSc 3.18's mirrors (docs/decisions.md, "PETSc 3.18's mirrors"). */
#include <stdio.h>
#include <stdlib.h>
#include "mesh_gmsh.h"

/* The nodes of a Gmsh element type: points, and first-order lines, triangles and tetrahedra (-1: another type). */
static PetscInt GmshTypeNodes(int type)
{
  switch (type) {
    case 15:
      return 1;
    case 1:
      return 2;
    case 2:
      return 3;
    case 4:
      return 4;
    default:
      return -1;
  }
}

/* Room for n more elements of m nodes each in *nodes and their sets in *set, of capacity *cap elements (doubled as
   needed), after len of them. */
static PetscErrorCode GrowElements(PetscInt **nodes, PetscInt **set, PetscInt *cap, PetscInt len, PetscInt n, PetscInt m)
{
  PetscInt *grown_nodes, *grown_set;

  PetscFunctionBeginUser;
  if (len + n <= *cap) PetscFunctionReturn(PETSC_SUCCESS);
  *cap = PetscMax(2 * *cap, len + n);
  PetscCall(PetscMalloc1(*cap * m, &grown_nodes));
  PetscCall(PetscMalloc1(*cap, &grown_set));
  PetscCall(PetscArraycpy(grown_nodes, *nodes, len * m));
  PetscCall(PetscArraycpy(grown_set, *set, len));
  PetscCall(PetscFree(*nodes));
  PetscCall(PetscFree(*set));
  *nodes = grown_nodes;
  *set   = grown_set;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The mesh Gmsh made (rank 0), numbered as PETSc's Gmsh reader numbers the file Gmsh would write (mesh_gmsh_build.c):
   the elements that file saves (where the model has physical groups, those of their entities, unless the model sets
   Mesh.SaveAll), in its order (the entities of dimension 0 to dim, each by tag), the nodes they use in Gmsh's node
   order (the same entities'), the cells oriented as DMPlexReorderCell() orients them, and the physical groups' names. */
PetscErrorCode MeshSimplicesFromGmsh(PetscInt dim, MeshSimplices *s)
{
  size_t    *node_tags = NULL, nnodes = 0, ncoord = 0, npar = 0, ngroups = 0;
  double    *xyz = NULL, *par = NULL, save_all = 0.0;
  int       *groups = NULL;
  PetscInt  *index, *vertex, tag_max = 0, ccap = 0, fcap = 0;
  PetscBool *used;

  PetscFunctionBeginUser;
  PetscCall(PetscMemzero(s, sizeof(*s)));
  s->dim = dim;
  GmshCall(gmsh_api.gmshModelMeshGetNodes(&node_tags, &nnodes, &xyz, &ncoord, &par, &npar, -1, -1, 0, 0, &ierr_gmsh), "get the mesh's nodes");
  for (size_t i = 0; i < nnodes; ++i) tag_max = PetscMax(tag_max, (PetscInt)node_tags[i]);
  PetscCall(PetscMalloc1(tag_max + 1, &index));
  for (PetscInt t = 0; t <= tag_max; ++t) index[t] = -1;
  for (size_t i = 0; i < nnodes; ++i) index[node_tags[i]] = (PetscInt)i;
  PetscCall(PetscCalloc2(nnodes + 1, &used, nnodes + 1, &vertex));
  GmshCall(gmsh_api.gmshModelGetPhysicalGroups(&groups, &ngroups, -1, &ierr_gmsh), "list the physical groups");
  for (size_t g = 0; g < ngroups / 2; ++g) { /* the names, as the file's $PhysicalNames; dim, tag pairs */
    char *name = NULL;

    GmshCall(gmsh_api.gmshModelGetPhysicalName(groups[2 * g], groups[2 * g + 1], &name, &ierr_gmsh), "name a physical group");
    if (name && name[0] && strlen(name) < sizeof(s->names[0].name) && s->nnames < MESH_MAX_NAMES) {
      s->names[s->nnames].dim = groups[2 * g];
      s->names[s->nnames].tag = groups[2 * g + 1];
      PetscCall(PetscStrncpy(s->names[s->nnames].name, name, sizeof(s->names[0].name)));
      s->nnames++;
    }
    gmsh_api.gmshFree(name);
  }
  gmsh_api.gmshFree(groups);
  GmshCall(gmsh_api.gmshOptionGetNumber("Mesh.SaveAll", &save_all, &ierr_gmsh), "get Mesh.SaveAll");
  for (int d = 0; d <= (int)dim; ++d) {
    int   *dimtags = NULL;
    size_t nent    = 0;

    GmshCall(gmsh_api.gmshModelGetEntities(&dimtags, &nent, d, &ierr_gmsh), "list the model's entities");
    for (size_t e = 0; e < nent / 2; ++e) { /* dim, tag pairs */
      int     *phys = NULL, *types = NULL;
      size_t   nphys = 0, ntypes = 0, *etags_n = NULL, netags = 0, *enodes_n = NULL, nenodes = 0, **etags = NULL, **enodes = NULL;
      PetscInt first;

      GmshCall(gmsh_api.gmshModelGetPhysicalGroupsForEntity(d, dimtags[2 * e + 1], &phys, &nphys, &ierr_gmsh), "list an entity's physical groups");
      first = nphys ? (PetscInt)phys[0] : -1;
      gmsh_api.gmshFree(phys);
      if (ngroups && !nphys && save_all == 0.0) continue; /* not saved */
      GmshCall(gmsh_api.gmshModelMeshGetElements(&types, &ntypes, &etags, &etags_n, &netags, &enodes, &enodes_n, &nenodes, d, dimtags[2 * e + 1],
                                                 &ierr_gmsh),
               "get an entity's elements");
      for (size_t t = 0; t < ntypes; ++t) {
        const PetscInt  nn = GmshTypeNodes(types[t]), count = nn > 0 ? (PetscInt)(enodes_n[t] / (size_t)nn) : 0;
        const PetscBool cell = (PetscBool)(d == (int)dim), face = (PetscBool)(d == (int)dim - 1);

        PetscCheck(nn > 0, PETSC_COMM_SELF, PETSC_ERR_SUP, "Gmsh made elements of type %d (first-order simplices only)", types[t]);
        if (cell) PetscCall(GrowElements(&s->cells, &s->cell_set, &ccap, s->ncells, count, nn));
        if (face) PetscCall(GrowElements(&s->faces, &s->face_set, &fcap, s->nfaces, count, nn));
        for (PetscInt i = 0; i < count; ++i) {
          for (PetscInt k = 0; k < nn; ++k) {
            const size_t   tag = enodes[t][i * nn + k];
            const PetscInt at  = tag <= (size_t)tag_max ? index[tag] : -1;

            PetscCheck(at >= 0, PETSC_COMM_SELF, PETSC_ERR_LIB, "Gmsh's element names node %zu, which its nodes do not have", tag);
            used[at] = PETSC_TRUE;
            if (cell) s->cells[(s->ncells + i) * nn + k] = at;
            if (face) s->faces[(s->nfaces + i) * nn + k] = at;
          }
          if (cell) s->cell_set[s->ncells + i] = first;
          if (face) s->face_set[s->nfaces + i] = first;
        }
        if (cell) s->ncells += count;
        if (face) s->nfaces += count;
        gmsh_api.gmshFree(etags[t]);
        gmsh_api.gmshFree(enodes[t]);
      }
      gmsh_api.gmshFree(types);
      gmsh_api.gmshFree(etags);
      gmsh_api.gmshFree(etags_n);
      gmsh_api.gmshFree(enodes);
      gmsh_api.gmshFree(enodes_n);
    }
    gmsh_api.gmshFree(dimtags);
  }
  for (size_t i = 0; i < nnodes; ++i) vertex[i] = used[i] ? s->nverts++ : -1; /* PETSc's vertexMap */
  /* the coordinates as the file Gmsh writes holds them, to 16 significant digits: Gmsh's own doubles differ by an ulp,
     and through the remeshing's sensitivity (the sizes, the marking's order, Gmsh's insertions) an ulp moves the later
     cycles' meshes, so that -mesh_remeshed_petsc_read would no longer give the same run */
  PetscCall(PetscMalloc1(s->nverts * dim + 1, &s->coords));
  for (size_t i = 0; i < nnodes; ++i)
    if (vertex[i] >= 0)
      for (PetscInt j = 0; j < dim; ++j) {
        char digits[32];

        (void)snprintf(digits, sizeof(digits), "%.16g", xyz[3 * i + j]);
        s->coords[vertex[i] * dim + j] = (PetscReal)strtod(digits, NULL);
      }
  for (PetscInt c = 0; c < s->ncells; ++c) {
    for (PetscInt k = 0; k <= dim; ++k) s->cells[c * (dim + 1) + k] = vertex[s->cells[c * (dim + 1) + k]];
    PetscCall(DMPlexInvertCell(dim == 2 ? DM_POLYTOPE_TRIANGLE : DM_POLYTOPE_TETRAHEDRON, &s->cells[c * (dim + 1)]));
  }
  for (PetscInt f = 0; f < s->nfaces * dim; ++f) s->faces[f] = vertex[s->faces[f]];
  gmsh_api.gmshFree(node_tags);
  gmsh_api.gmshFree(xyz);
  gmsh_api.gmshFree(par);
  PetscCall(PetscFree(index));
  PetscCall(PetscFree2(used, vertex));
  PetscFunctionReturn(PETSC_SUCCESS);
}

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

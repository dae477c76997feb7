/* Checks of a mesh read from a file, made before anything is assembled, for what the discretization cannot handle and
   would otherwise solve into a wrong answer without a word:
   - more than one cell type (a Gmsh mesh of triangles and quadrilaterals): the discretization holds one PetscFE for
     every cell, so the cells of the other type would be integrated with the wrong element (invalid reads, |u| = 1e78);
   - a high-order (curved) mesh: PETSc 3.18 reads the nodes of a 6-node triangle as a P2 coordinate field, which the
     P1 sections and the contact geometry (vertex coordinates only) do not follow;
   - two cells on the same vertices: the duplicate adds its stiffness twice, and the faces between them are seen as
     interior;
   and of the face sets of the boundary families (mesh_check.c's MeshCountInteriorFaces()): a boundary condition on faces
   inside the body. */
#include <petscsf.h>
#include "mesh.h"

/* Refuses a mesh whose cells are not all of one polytope type; the message names each type and its count. */
static PetscErrorCode MeshCheckCellTypes(DM dm, const char filename[])
{
  MPI_Comm comm = PetscObjectComm((PetscObject)dm);
  PetscInt cStart, cEnd, count[DM_NUM_POLYTOPES], ntypes = 0;
  char     list[512] = "";

  PetscFunctionBeginUser;
  for (PetscInt t = 0; t < DM_NUM_POLYTOPES; ++t) count[t] = 0;
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  for (PetscInt c = cStart; c < cEnd; ++c) {
    DMPolytopeType ct;

    PetscCall(DMPlexGetCellType(dm, c, &ct));
    ++count[ct];
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, count, DM_NUM_POLYTOPES, MPIU_INT, MPI_SUM, comm));
  for (PetscInt t = 0; t < DM_NUM_POLYTOPES; ++t) {
    char item[96];

    if (!count[t]) continue;
    PetscCall(PetscSNPrintf(item, sizeof(item), "%s%" PetscInt_FMT " %s", ntypes ? ", " : "", count[t], DMPolytopeTypes[t]));
    PetscCall(PetscStrlcat(list, item, sizeof(list)));
    ++ntypes;
  }
  PetscCheck(ntypes <= 1, comm, PETSC_ERR_USER_INPUT,
             "The mesh file '%s' mixes cell types (%s): the solver discretizes every cell with one element, so mesh the whole body with one "
             "type (Gmsh: all triangles/tetrahedra, or recombine every surface into quadrilaterals/hexahedra)",
             filename, list);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Refuses a mesh read with coordinates on points other than its vertices: a high-order (curved) mesh. */
static PetscErrorCode MeshCheckFirstOrder(DM dm, const char filename[])
{
  MPI_Comm     comm = PetscObjectComm((PetscObject)dm);
  PetscSection cs;
  PetscInt     vStart, vEnd, pStart, pEnd, nodes = 0, nv, cStart, cEnd, per_cell = 0;

  PetscFunctionBeginUser;
  PetscCall(DMGetCoordinateSection(dm, &cs));
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  PetscCall(PetscSectionGetChart(cs, &pStart, &pEnd));
  for (PetscInt p = pStart; p < pEnd; ++p) {
    PetscInt dof;

    if (p >= vStart && p < vEnd) continue;
    PetscCall(PetscSectionGetDof(cs, p, &dof));
    nodes += dof > 0;
  }
  nv = vEnd - vStart;
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  if (cEnd > cStart) PetscCall(DMPlexGetConeSize(dm, cStart, &per_cell));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &nodes, 1, MPIU_INT, MPI_SUM, comm));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &nv, 1, MPIU_INT, MPI_SUM, comm));
  PetscCheck(nodes == 0, comm, PETSC_ERR_USER_INPUT,
             "The mesh file '%s' holds high-order (curved) elements: %" PetscInt_FMT " edges, faces or cells carry nodes besides the %" PetscInt_FMT
             " vertices. The solver takes its geometry from the vertices (first-order cells); export a first-order mesh (Gmsh: "
             "Mesh.ElementOrder = 1, or gmsh -order 1), and ask for P2 unknowns with -displacement_petscspace_degree 2 if you want them",
             filename, nodes, nv);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* A cell's sorted vertex numbers, for finding two cells on the same vertices. */
#define MESH_CHECK_MAX_VERTS 8
typedef struct {
  PetscInt n, v[MESH_CHECK_MAX_VERTS], cell;
} CellKey;

static int CompareCellKeys(const void *a, const void *b)
{
  const CellKey *x = (const CellKey *)a, *y = (const CellKey *)b;

  if (x->n != y->n) return x->n < y->n ? -1 : 1;
  for (PetscInt i = 0; i < x->n; ++i)
    if (x->v[i] != y->v[i]) return x->v[i] < y->v[i] ? -1 : 1;
  return 0;
}

/* Refuses two cells on the same set of vertices (a cell listed twice in the file). Each rank checks the cells it read:
   a Gmsh or ExodusII file is read whole on the first rank. */
static PetscErrorCode MeshCheckDuplicateCells(DM dm, const char filename[])
{
  MPI_Comm    comm = PetscObjectComm((PetscObject)dm);
  PetscInt    cStart, cEnd, ndup = 0, first[2] = {-1, -1};
  CellKey    *keys;
  MeshClosure mc;

  PetscFunctionBeginUser;
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  PetscCall(PetscMalloc1(cEnd - cStart, &keys));
  PetscCall(MeshClosureCreate(dm, &mc)); /* the closures' vertices without a cell-type lookup per point: a tenth of the time */
  for (PetscInt c = cStart; c < cEnd; ++c) {
    CellKey *k = &keys[c - cStart];

    k->cell = c;
    PetscCall(MeshClosureVertices(&mc, c, MESH_CHECK_MAX_VERTS, &k->n, k->v));
    PetscCall(PetscSortInt(k->n, k->v));
  }
  PetscCall(MeshClosureDestroy(&mc));
  if (cEnd > cStart) qsort(keys, (size_t)(cEnd - cStart), sizeof(CellKey), CompareCellKeys); /* a rank without cells has no array */
  for (PetscInt i = 1; i < cEnd - cStart; ++i)
    if (!CompareCellKeys(&keys[i - 1], &keys[i])) {
      if (!ndup) {
        first[0] = PetscMin(keys[i - 1].cell, keys[i].cell) - cStart;
        first[1] = PetscMax(keys[i - 1].cell, keys[i].cell) - cStart;
      }
      ++ndup;
    }
  PetscCall(PetscFree(keys));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &ndup, 1, MPIU_INT, MPI_SUM, comm));
  PetscCheck(ndup == 0, comm, PETSC_ERR_USER_INPUT,
             "The mesh file '%s' has %" PetscInt_FMT " duplicate cell(s): cells on the same vertices as another (the first pair: cells %" PetscInt_FMT
             " and %" PetscInt_FMT
             ", counted from 0 in the order read). Each would add its stiffness twice; remove the duplicates (Gmsh: Coherence Mesh, or check the "
             "physical groups for a surface or volume listed twice)",
             filename, ndup, first[0], first[1]);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The checks of a mesh read from a file, on the mesh as read (before the distribution). */
PetscErrorCode MeshCheckFile(DM dm, const char filename[])
{
  PetscFunctionBeginUser;
  PetscCall(MeshCheckFirstOrder(dm, filename));
  PetscCall(MeshCheckCellTypes(dm, filename));
  PetscCall(MeshCheckDuplicateCells(dm, filename));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The number, over all ranks, of the n local faces given that have a cell on each side: interior faces. A face on the
   boundary between two ranks has one cell on each of them, so the cells are summed onto the face's owner (the point
   SF) before they are counted. */
PetscErrorCode MeshCountInteriorFaces(DM dm, PetscInt n, const PetscInt faces[], PetscInt *ninterior)
{
  PetscSF         sf;
  PetscInt        pStart, pEnd, nroots, nleaves, count = 0;
  const PetscInt *ilocal;
  PetscInt       *cells, *leaf_cells, *is_leaf;

  PetscFunctionBeginUser;
  PetscCall(DMPlexGetChart(dm, &pStart, &pEnd));
  PetscCall(DMGetPointSF(dm, &sf));
  PetscCall(PetscSFGetGraph(sf, &nroots, &nleaves, &ilocal, NULL));
  PetscCall(PetscCalloc3(pEnd - pStart, &cells, pEnd - pStart, &leaf_cells, pEnd - pStart, &is_leaf));
  for (PetscInt i = 0; i < n; ++i) PetscCall(DMPlexGetSupportSize(dm, faces[i], &cells[faces[i] - pStart]));
  if (nroots >= 0) {
    for (PetscInt l = 0; l < nleaves; ++l) is_leaf[(ilocal ? ilocal[l] : l) - pStart] = 1;
    for (PetscInt p = 0; p < pEnd - pStart; ++p) leaf_cells[p] = is_leaf[p] ? cells[p] : 0;
    PetscCall(PetscSFReduceBegin(sf, MPIU_INT, leaf_cells, cells, MPI_SUM));
    PetscCall(PetscSFReduceEnd(sf, MPIU_INT, leaf_cells, cells, MPI_SUM));
  }
  for (PetscInt i = 0; i < n; ++i) count += !is_leaf[faces[i] - pStart] && cells[faces[i] - pStart] > 1;
  PetscCall(PetscFree3(cells, leaf_cells, is_leaf));
  PetscCall(MPIU_Allreduce(&count, ninterior, 1, MPIU_INT, MPI_SUM, PetscObjectComm((PetscObject)dm)));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* A mesh file's boundary that turns by a small angle at its ridges (the vertices between two boundary edges in 2D, the
   edges between two boundary faces in 3D) approximates a curved boundary by its chords. Refinement inside the solver
   (-dm_refine, -contact_grid_sequence, -adapt_cycles) splits the chords at their midpoints and keeps that polygon, so
   that the refined meshes converge to the answer on the file's polygon, not on the curved body (docs/decisions.md,
   "Chords"). count: the
   ridges where the outward normals of the two boundary faces turn by more than MESH_FLAT_ANGLE and at most
   MESH_CURVED_ANGLE (a polygon's corners turn by more; the straight pieces by nothing), over all ranks; x, where count
   > 0: one of them. A ridge whose two faces lie on different ranks is not seen (the count is a lower bound). */
#define MESH_FLAT_ANGLE 1e-6                        /* radians: straight */
#define MESH_CURVED_ANGLE (20.0 * PETSC_PI / 180.0) /* a chord of a circle of radius R spans h/R, up to 20 degrees */
PetscErrorCode MeshCountCurvedRidges(DM dm, PetscInt *count, PetscReal x[3])
{
  MPI_Comm   comm = PetscObjectComm((PetscObject)dm);
  DMLabel    bnd;
  PetscInt   dim, fStart, fEnd, rStart, rEnd, local = 0;
  PetscInt  *nface;
  PetscReal *normal, where[4] = {0, 0, 0, 0}, all[3];

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  {
    Vec coords;

    PetscCall(DMGetCoordinatesLocal(
        dm, &coords)); /* collective: makes the local coordinates the face geometry reads (a mesh read from HDF5 has none yet) */
  }
  PetscCall(DMPlexGetHeightStratum(dm, 1, &fStart, &fEnd)); /* faces */
  PetscCall(DMPlexGetHeightStratum(dm, 2, &rStart, &rEnd)); /* ridges: vertices in 2D, edges in 3D */
  PetscCall(DMLabelCreate(PETSC_COMM_SELF, "curved_check_boundary", &bnd));
  PetscCall(DMPlexMarkBoundaryFaces(dm, 1, bnd));
  PetscCall(PetscCalloc2(rEnd - rStart, &nface, 6 * (rEnd - rStart), &normal));
  for (PetscInt f = fStart; f < fEnd; ++f) {
    const PetscInt *cone;
    PetscInt        val, nc;
    PetscReal       n[3] = {0, 0, 0}, xf[3], area;

    PetscCall(DMLabelGetValue(bnd, f, &val));
    if (val != 1) continue;
    PetscCall(MeshFaceOutwardGeometry(dm, f, dim, n, xf, &area));
    if (!(area > 0.0)) continue;
    PetscCall(DMPlexGetConeSize(dm, f, &nc));
    PetscCall(DMPlexGetCone(dm, f, &cone));
    for (PetscInt k = 0; k < nc; ++k) {
      const PetscInt r = cone[k] - rStart;

      if (r < 0 || r >= rEnd - rStart) continue;
      if (nface[r] < 2)
        for (PetscInt d = 0; d < dim; ++d) normal[6 * r + 3 * nface[r] + d] = n[d];
      nface[r]++;
    }
  }
  for (PetscInt r = 0; r < rEnd - rStart; ++r) {
    PetscReal dot = 0.0, angle;

    if (nface[r] != 2) continue;
    for (PetscInt d = 0; d < dim; ++d) dot += normal[6 * r + d] * normal[6 * r + 3 + d];
    angle = PetscAcosReal(PetscMin(1.0, PetscMax(-1.0, dot)));
    if (angle > MESH_FLAT_ANGLE && angle <= MESH_CURVED_ANGLE) {
      if (!local) {
        PetscCall(MeshPointPosition(dm, rStart + r, where)); /* a vertex in 2D; an edge's centroid in 3D */
        where[3] = 1.0;
      }
      ++local;
    }
  }
  PetscCall(PetscFree2(nface, normal));
  PetscCall(DMLabelDestroy(&bnd));
  PetscCall(MPIU_Allreduce(&local, count, 1, MPIU_INT, MPI_SUM, comm));
  { /* the example of the first rank that has one */
    PetscMPIInt rank, size, first, mine;

    PetscCallMPI(MPI_Comm_rank(comm, &rank));
    PetscCallMPI(MPI_Comm_size(comm, &size));
    mine = where[3] > 0.0 ? rank : size;
    PetscCall(MPIU_Allreduce(&mine, &first, 1, MPI_INT, MPI_MIN, comm));
    for (PetscInt d = 0; d < 3; ++d) all[d] = where[d];
    if (first < size) PetscCallMPI(MPI_Bcast(all, 3, MPIU_REAL, first, comm));
  }
  for (PetscInt d = 0; d < 3; ++d) x[d] = all[d];
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The bulk elastic matrix K for P1 on simplices, without PetscFE: the preallocation from the mesh's edges (one rank: a
   block per vertex, or a row per dof where a vertex is partly constrained) or by a MATPREALLOCATOR dry run of the cell loop (DMPlex's adjacency-based
   preallocation is slow in 3.18), and closed-form element matrices B^T D B |T|. The result is the matrix of DMCreateMatrix() +
   DMPlexSNESComputeJacobianFEM(): same type, sizes, block size, local-to-global mapping, nonzero pattern and values; the rows and columns of
   constrained dofs are absent. */
#include "mesh.h"
#include "discretization.h"
#include "physics.h"

const char *const AssemblyTypes[] = {"auto", "fe", "p1", "AssemblyType", "ASSEMBLY_", NULL};

static PetscLogEvent ASSEMBLY_P1_Preallocate, ASSEMBLY_P1_Fill;

/* Why the P1 path does not apply to dm with displacements of this degree, NULL when it does; the same answer on every rank. */
static PetscErrorCode AssemblyP1Applies(DM dm, PetscInt degree, const char **reason)
{
  static const char *const reasons[] = {NULL,
                                        "the mesh dimension is not 2 or 3",
                                        "the cells are not all triangles (2D) or tetrahedra (3D)",
                                        "the displacement is not of degree 1",
                                        "the discretization is not one field with dim components",
                                        "the coordinates are not one vector of dim components per vertex (embedded, periodic or high-order mesh)",
                                        "the matrix type is not aij, baij or sbaij (-dm_mat_type)"};
  const char *const        types[]   = {MATAIJ, MATSEQAIJ, MATMPIAIJ, MATBAIJ, MATSEQBAIJ, MATMPIBAIJ, MATSBAIJ, MATSEQSBAIJ, MATMPISBAIJ};
  PetscInt                 dim, cdim, cStart, cEnd, vStart, vEnd, nf, nc, size, csize;
  PetscMPIInt              code = 0, gcode;
  PetscSection             section, csection;
  PetscBool                localized, known = PETSC_FALSE;
  MatType                  mtype;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMGetCoordinateDim(dm, &cdim));
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  PetscCall(DMGetNumFields(dm, &nf));
  PetscCall(DMGetLocalSection(dm, &section));
  PetscCall(PetscSectionGetStorageSize(section, &size));
  PetscCall(DMGetCoordinatesLocalized(dm, &localized));
  PetscCall(DMGetCoordinateSection(dm, &csection));
  PetscCall(PetscSectionGetStorageSize(csection, &csize));
  PetscCall(DMGetMatType(dm, &mtype));
  for (size_t i = 0; i < sizeof(types) / sizeof(types[0]); ++i) {
    PetscBool same;

    PetscCall(PetscStrcmp(mtype, types[i], &same));
    known = (PetscBool)(known || same);
  }
  nc = 0;
  if (nf == 1) PetscCall(PetscSectionGetFieldComponents(section, 0, &nc));
  if (dim != 2 && dim != 3) code = 1;
  if (!code) { /* the type of dimension dim is only a cell's: all cells are simplices if that many points are */
    DMLabel  ct_label;
    PetscInt nsimplices;

    PetscCall(DMPlexGetCellTypeLabel(dm, &ct_label));
    PetscCall(DMLabelGetStratumSize(ct_label, dim == 2 ? DM_POLYTOPE_TRIANGLE : DM_POLYTOPE_TETRAHEDRON, &nsimplices));
    if (nsimplices != cEnd - cStart) code = 2;
  }
  if (!code && degree != 1) code = 3;
  if (!code && (nf != 1 || nc != dim || size != (vEnd - vStart) * dim)) code = 4;
  if (!code && (cdim != dim || localized || csize != (vEnd - vStart) * dim)) code = 5;
  if (!code && !known) code = 6;
  PetscCallMPI(MPI_Allreduce(&code, &gcode, 1, MPI_INT, MPI_MAX, PetscObjectComm((PetscObject)dm)));
  *reason = reasons[gcode];
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* -assembly and -assembly_check, read once before any set-up. */
PetscErrorCode AssemblyGetOptions(MPI_Comm comm, AssemblyType *requested, PetscBool *check)
{
  PetscFunctionBeginUser;
  PetscOptionsBegin(comm, NULL, "Assembly of the bulk matrix", "Signorini");
  *requested = ASSEMBLY_AUTO;
  PetscCall(PetscOptionsEnum("-assembly", "Bulk matrix K: auto (p1 where it applies, else fe), fe (PetscFE) or p1 (P1 simplices, closed form)",
                             "SolverAssembleBulk", AssemblyTypes, (PetscEnum)*requested, (PetscEnum *)requested, NULL));
  *check = PETSC_FALSE;
  PetscCall(PetscOptionsBool("-assembly_check", "Assemble K both ways and print ||K_p1 - K_fe||_F / ||K_fe||_F", "SolverAssembleBulk", *check, check,
                             NULL));
  PetscOptionsEnd();
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The assembly of this mesh's K: the requested one (-assembly), with auto resolved (p1 where it applies to displacements
   of this degree, fe otherwise); check (-assembly_check) needs the p1 path. PetscFE's closures then look each point's
   cell type up in an index made once (MeshIndexCellTypes()). */
PetscErrorCode AssemblyResolve(DM dm, AssemblyType requested, PetscInt degree, PetscBool check, AssemblyType *assembly)
{
  MPI_Comm    comm   = PetscObjectComm((PetscObject)dm);
  const char *reason = NULL;

  PetscFunctionBeginUser;
  *assembly = requested;
  PetscCall(AssemblyP1Applies(dm, degree, &reason));
  PetscCheck(*assembly != ASSEMBLY_P1 || !reason, comm, PETSC_ERR_USER_INPUT,
             "-assembly p1 needs P1 displacements on triangles or tetrahedra, but %s: use -assembly fe or auto", reason);
  PetscCheck(!check || !reason, comm, PETSC_ERR_USER_INPUT, "-assembly_check compares with the P1 assembly, which does not apply: %s", reason);
  if (*assembly == ASSEMBLY_AUTO) *assembly = reason ? ASSEMBLY_FE : ASSEMBLY_P1;
  if (*assembly == ASSEMBLY_FE) PetscCall(MeshIndexCellTypes(dm)); /* before PetscFE's closure per cell */
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Global index of each dof of each local vertex, as DMPlex's closure indices give them (MeshPointGlobalIndices()). */
static PetscErrorCode AssemblyP1VertexIndices(DM dm, PetscInt **vidx)
{
  PetscSection section, gsection;
  PetscInt     dim, vStart, vEnd;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  PetscCall(DMGetLocalSection(dm, &section));
  PetscCall(DMGetGlobalSection(dm, &gsection));
  PetscCall(PetscMalloc1((vEnd - vStart) * dim, vidx));
  for (PetscInt v = vStart; v < vEnd; ++v) PetscCall(MeshPointGlobalIndices(section, gsection, v, dim, &(*vidx)[(v - vStart) * dim]));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The dim + 1 vertices of each local cell, [cells][dim + 1], by walking the cones down to the vertices (without
   DMPlexGetTransitiveClosure()'s cell-type lookup for every point). */
static PetscErrorCode AssemblyP1CellVertices(DM dm, PetscInt **cverts)
{
  PetscInt     dim, cStart, cEnd, vStart, vEnd, *cones;
  PetscSection cone_section;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  PetscCall(DMPlexGetConeSection(dm, &cone_section)); /* the cones read directly, as DMPlexGetCone() gives them */
  PetscCall(DMPlexGetCones(dm, &cones));
  PetscCall(PetscMalloc1((cEnd - cStart) * (dim + 1), cverts));
  for (PetscInt c = cStart; c < cEnd; ++c) {
    PetscInt *verts = &(*cverts)[(c - cStart) * (dim + 1)], stack[64], top = 0, nv = 0;

    stack[top++] = c;
    while (top) {
      const PetscInt p = stack[--top];

      if (p >= vStart && p < vEnd) {
        PetscBool seen = PETSC_FALSE;

        for (PetscInt i = 0; i < nv; ++i) seen = (PetscBool)(seen || verts[i] == p);
        if (!seen) {
          PetscCheck(nv <= dim, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Cell %" PetscInt_FMT " has more than %" PetscInt_FMT " vertices", c, dim + 1);
          verts[nv++] = p;
        }
      } else {
        const PetscInt *cone;
        PetscInt        ncone, off;

        PetscCall(PetscSectionGetDof(cone_section, p, &ncone));
        PetscCall(PetscSectionGetOffset(cone_section, p, &off));
        cone = &cones[off];
        PetscCheck(top + ncone <= 64, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Cone walk of cell %" PetscInt_FMT " too deep", c);
        for (PetscInt i = 0; i < ncone; ++i) stack[top++] = cone[i];
      }
    }
    PetscCheck(nv == dim + 1, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Cell %" PetscInt_FMT " has %" PetscInt_FMT " vertices", c, nv);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The block size DMCreateMatrix() gives: the dofs per point, 1 if a point is partially constrained or the points differ
   (scanned over the vertices, the only points with P1 dofs). */
static PetscErrorCode AssemblyP1BlockSize(DM dm, PetscInt *bs)
{
  PetscSection gsection;
  PetscInt     vStart, vEnd, b = -1, local[2], minmax[2];

  PetscFunctionBeginUser;
  PetscCall(DMGetGlobalSection(dm, &gsection));
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd)); /* the vertices: the other points of a P1 field have no dofs */
  for (PetscInt v = vStart; v < vEnd; ++v) {
    PetscInt dof, cdof, bdof;

    PetscCall(PetscSectionGetDof(gsection, v, &dof));
    PetscCall(PetscSectionGetConstraintDof(gsection, v, &cdof));
    dof  = dof < 0 ? -(dof + 1) : dof;
    bdof = cdof && (dof - cdof) ? 1 : dof;
    if (dof) {
      if (b < 0)
        b = bdof;
      else if (b != bdof) {
        b = 1;
        break;
      }
    }
  }
  local[0] = b < 0 ? PETSC_MAX_INT : b;
  local[1] = b;
  PetscCall(PetscGlobalMinMaxInt(PetscObjectComm((PetscObject)dm), local, minmax));
  *bs = PetscMax(1, minmax[0] != minmax[1] ? 1 : minmax[0]);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The exact preallocation of K on one rank with a block per vertex, from its block pattern (AssemblyP1BlockPattern():
   a block row holds its vertex and the free neighbours along its edges); for the matrix types the CSR build of
   AssemblyP1CreateSeqAIJ() does not take (BAIJ, SBAIJ, -mat_type). */
static PetscErrorCode AssemblyP1PreallocateFromEdges(DM dm, PetscInt bs, PetscInt nlocal, const PetscInt vidx[], Mat K, PetscBool *done)
{
  PetscMPIInt size;
  PetscInt    dim, depth, nb = nlocal / bs, *bptr, *bcol, *dnz, *dnzu, *onz;

  PetscFunctionBeginUser;
  *done = PETSC_FALSE;
  PetscCallMPI(MPI_Comm_size(PetscObjectComm((PetscObject)dm), &size));
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMPlexGetDepth(dm, &depth));
  if (size > 1 || bs != dim || depth != dim) PetscFunctionReturn(PETSC_SUCCESS); /* MATPREALLOCATOR then */
  PetscCall(AssemblyP1BlockPattern(dm, bs, nb, vidx, &bptr, &bcol));
  PetscCall(PetscCalloc3(nb, &dnz, nb, &dnzu, nb, &onz));
  for (PetscInt r = 0; r < nb; ++r) {
    dnz[r] = bptr[r + 1] - bptr[r];
    for (PetscInt k = bptr[r]; k < bptr[r + 1]; ++k) dnzu[r] += bcol[k] >= r;
  }
  PetscCall(MatXAIJSetPreallocation(K, bs, dnz, onz, dnzu, onz));
  PetscCall(MatSetOption(K, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_TRUE));
  PetscCall(PetscFree3(dnz, dnzu, onz));
  PetscCall(PetscFree(bptr));
  PetscCall(PetscFree(bcol));
  *done = PETSC_TRUE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The exact preallocation of K on one rank with a row per dof (bs = 1: some vertex is partly constrained, as on a slip
   face): the row of a free component of vertex v holds the free components of v and of its neighbours along the edges,
   counted edge by edge, in and on or above the diagonal (for sbaij). */
static PetscErrorCode AssemblyP1PreallocateScalar(DM dm, PetscInt nlocal, const PetscInt vidx[], Mat K, PetscBool *done)
{
  PetscMPIInt size;
  PetscInt    dim, depth, vStart, vEnd, eStart, eEnd, *dnz, *dnzu, *onz;

  PetscFunctionBeginUser;
  *done = PETSC_FALSE;
  PetscCallMPI(MPI_Comm_size(PetscObjectComm((PetscObject)dm), &size));
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMPlexGetDepth(dm, &depth));
  if (size > 1 || depth != dim) PetscFunctionReturn(PETSC_SUCCESS); /* MATPREALLOCATOR then */
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  PetscCall(DMPlexGetDepthStratum(dm, 1, &eStart, &eEnd));
  PetscCall(PetscCalloc3(nlocal, &dnz, nlocal, &dnzu, nlocal, &onz));
  for (PetscInt v = vStart; v < vEnd; ++v) { /* the vertex's own block */
    const PetscInt *g = &vidx[(v - vStart) * dim];

    for (PetscInt a = 0; a < dim; ++a)
      for (PetscInt b = 0; b < dim && g[a] >= 0; ++b) {
        if (g[b] < 0) continue;
        PetscCheck(g[a] < nlocal && g[b] < nlocal, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Vertex %" PetscInt_FMT " has a dof outside the rows", v);
        ++dnz[g[a]];
        dnzu[g[a]] += g[b] >= g[a];
      }
  }
  for (PetscInt e = eStart; e < eEnd; ++e) { /* the blocks of the edge's two vertices, both ways */
    const PetscInt *cone, *ga, *gb;

    PetscCall(DMPlexGetCone(dm, e, &cone));
    ga = &vidx[(cone[0] - vStart) * dim];
    gb = &vidx[(cone[1] - vStart) * dim];
    for (PetscInt a = 0; a < dim; ++a)
      for (PetscInt b = 0; b < dim; ++b) {
        if (ga[a] < 0 || gb[b] < 0) continue;
        ++dnz[ga[a]];
        ++dnz[gb[b]];
        dnzu[ga[a]] += gb[b] >= ga[a];
        dnzu[gb[b]] += ga[a] >= gb[b];
      }
  }
  PetscCall(MatXAIJSetPreallocation(K, 1, dnz, onz, dnzu, onz));
  PetscCall(MatSetOption(K, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_TRUE));
  PetscCall(PetscFree3(dnz, dnzu, onz));
  *done = PETSC_TRUE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Preallocates K by a dry run of the cell loop into a MATPREALLOCATOR whose rows and columns are blocks of bs dofs (one
   per vertex when bs = dim), which also counts the entries of rows owned by other ranks. Its pattern, filled into a
   helper matrix of blocks, gives the exact counts of blocks per block row, in and off the diagonal part and on and above
   the diagonal (for sbaij); AssemblyP1PreallocateFromEdges() and AssemblyP1PreallocateScalar() are tried first. */
static PetscErrorCode AssemblyP1Preallocate(DM dm, PetscInt bs, PetscInt nlocal, const PetscInt vidx[], const PetscInt cverts[], Mat K)
{
  MPI_Comm  comm = PetscObjectComm((PetscObject)dm);
  Mat       pre, H;
  PetscInt  dim, cStart, cEnd, vStart, vEnd, nb = nlocal / bs, rstart, rend, *dnz, *onz, *dnzu, *onzu;
  PetscBool done;

  PetscFunctionBeginUser;
  PetscCall(AssemblyP1PreallocateFromEdges(dm, bs, nlocal, vidx, K, &done));
  if (!done && bs == 1) PetscCall(AssemblyP1PreallocateScalar(dm, nlocal, vidx, K, &done));
  if (done) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  PetscCheck(bs == 1 || bs == dim, comm, PETSC_ERR_PLIB, "Block size %" PetscInt_FMT " is neither 1 nor dim", bs);
  PetscCall(MatCreate(comm, &pre));
  PetscCall(MatSetType(pre, MATPREALLOCATOR));
  PetscCall(MatSetSizes(pre, nb, nb, PETSC_DETERMINE, PETSC_DETERMINE));
  PetscCall(MatSetUp(pre));
  for (PetscInt c = cStart; c < cEnd; ++c) {
    PetscInt idx[12], n = 0;

    for (PetscInt a = 0; a <= dim; ++a) {
      const PetscInt *v = &vidx[(cverts[(c - cStart) * (dim + 1) + a] - vStart) * dim];

      if (bs == dim)
        idx[n++] = v[0] < 0 ? -1 : v[0] / bs; /* fully free or fully constrained */
      else
        for (PetscInt e = 0; e < dim; ++e) idx[n++] = v[e];
    }
    PetscCall(MatSetValues(pre, n, idx, n, idx, NULL, INSERT_VALUES));
  }
  PetscCall(MatAssemblyBegin(pre, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(pre, MAT_FINAL_ASSEMBLY));
  PetscCall(MatCreate(comm, &H));
  PetscCall(MatSetType(H, MATAIJ));
  PetscCall(MatSetSizes(H, nb, nb, PETSC_DETERMINE, PETSC_DETERMINE));
  PetscCall(MatPreallocatorPreallocate(pre, PETSC_TRUE, H));
  PetscCall(MatAssemblyBegin(H, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(H, MAT_FINAL_ASSEMBLY));
  PetscCall(MatDestroy(&pre));
  PetscCall(MatGetOwnershipRange(H, &rstart, &rend));
  PetscCall(PetscCalloc4(nb, &dnz, nb, &onz, nb, &dnzu, nb, &onzu));
  for (PetscInt i = rstart; i < rend; ++i) {
    const PetscInt *cols;
    PetscInt        ncols;

    PetscCall(MatGetRow(H, i, &ncols, &cols, NULL));
    for (PetscInt j = 0; j < ncols; ++j) {
      const PetscBool diag = (PetscBool)(cols[j] >= rstart && cols[j] < rend);

      if (diag)
        ++dnz[i - rstart];
      else
        ++onz[i - rstart];
      if (cols[j] >= i) {
        if (diag)
          ++dnzu[i - rstart];
        else
          ++onzu[i - rstart];
      }
    }
    PetscCall(MatRestoreRow(H, i, &ncols, &cols, NULL));
  }
  PetscCall(MatDestroy(&H));
  PetscCall(MatXAIJSetPreallocation(K, bs, dnz, onz, dnzu, onzu));
  PetscCall(MatSetOption(K, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_TRUE));
  PetscCall(PetscFree4(dnz, onz, dnzu, onzu));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* K of any type on any number of ranks: preallocated (AssemblyP1Preallocate()), then filled cell by cell through
   MatSetValues(), which also sends the entries of rows owned by other ranks. Ends the preallocation's log event. */
static PetscErrorCode AssemblyP1CreateAnyMatrix(DM dm, const Material *mat, PetscInt nlocal, PetscInt bs, const PetscInt vidx[],
                                                const PetscInt cverts[], ISLocalToGlobalMapping ltog, Mat *K)
{
  PetscSection       csection;
  Vec                coords;
  const PetscScalar *xa;
  MatType            mtype;
  PetscInt           dim, cStart, cEnd, vStart, vEnd;
  PetscBool          is_sbaij;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  PetscCall(DMGetMatType(dm, &mtype));
  PetscCall(MatCreate(PetscObjectComm((PetscObject)dm), K));
  PetscCall(MatSetSizes(*K, nlocal, nlocal, PETSC_DETERMINE, PETSC_DETERMINE));
  PetscCall(MatSetType(*K, mtype));
  PetscCall(MatSetBlockSize(*K, bs));
  PetscCall(MatSetFromOptions(*K));
  PetscCall(MatSetLocalToGlobalMapping(*K, ltog, ltog));

  PetscCall(AssemblyP1Preallocate(dm, bs, nlocal, vidx, cverts, *K));
  PetscCall(PetscObjectTypeCompareAny((PetscObject)*K, &is_sbaij, MATSEQSBAIJ, MATMPISBAIJ, ""));
  if (is_sbaij) PetscCall(MatSetOption(*K, MAT_IGNORE_LOWER_TRIANGULAR, PETSC_TRUE));
  PetscCall(PetscLogEventEnd(ASSEMBLY_P1_Preallocate, dm, 0, 0, 0));

  PetscCall(PetscLogEventBegin(ASSEMBLY_P1_Fill, dm, 0, 0, 0));
  PetscCall(DMGetCoordinateSection(dm, &csection));
  PetscCall(DMGetCoordinatesLocal(dm, &coords));
  PetscCall(VecGetArrayRead(coords, &xa));
  for (PetscInt c = cStart; c < cEnd; ++c) {
    PetscInt    idx[12], n = (dim + 1) * dim;
    PetscReal   x[12];
    PetscScalar Ke[144];

    PetscCall(AssemblyP1CellCoordinates(csection, xa, dim, &cverts[(c - cStart) * (dim + 1)], x));
    for (PetscInt a = 0; a <= dim; ++a)
      for (PetscInt e = 0; e < dim; ++e) idx[a * dim + e] = vidx[(cverts[(c - cStart) * (dim + 1) + a] - vStart) * dim + e];
    PetscCall(ElementP1Stiffness(dim, mat->lambda, mat->mu, x, Ke));
    PetscCall(MatSetValues(*K, n, idx, n, idx, Ke, ADD_VALUES));
  }
  PetscCall(VecRestoreArrayRead(coords, &xa));
  PetscCall(MatAssemblyBegin(*K, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(*K, MAT_FINAL_ASSEMBLY));
  PetscCall(PetscLogEventEnd(ASSEMBLY_P1_Fill, dm, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Creates and assembles K by the P1 path; the near-null space is left to the caller. */
PetscErrorCode AssemblyP1CreateMatrix(DM dm, const AssemblyP1Inputs *in, Mat *K)
{
  PetscSection           gsection;
  ISLocalToGlobalMapping ltog;
  PetscInt               nlocal, bs = 1, *vidx, *cverts;
  PetscBool              done;

  PetscFunctionBeginUser;
  if (!ASSEMBLY_P1_Fill) {
    PetscCall(PetscLogEventRegister("AssemblyP1Prealloc", DM_CLASSID, &ASSEMBLY_P1_Preallocate));
    PetscCall(PetscLogEventRegister("AssemblyP1Fill", DM_CLASSID, &ASSEMBLY_P1_Fill));
  }
  PetscCall(PetscLogEventBegin(ASSEMBLY_P1_Preallocate, dm, 0, 0, 0));
  PetscCall(DMGetGlobalSection(dm, &gsection));
  PetscCall(PetscSectionGetConstrainedStorageSize(gsection, &nlocal));
  PetscCall(AssemblyP1BlockSize(dm, &bs));
  PetscCall(AssemblyP1VertexIndices(dm, &vidx));
  PetscCall(AssemblyP1CellVertices(dm, &cverts));
  PetscCall(AssemblyP1CreateSeqAIJ(dm, in, nlocal, bs, vidx, cverts, K, &done));            /* one rank, AIJ: its own CSR arrays */
  if (!done) PetscCall(AssemblyP1CreateMPIAIJ(dm, in, nlocal, bs, vidx, cverts, K, &done)); /* several ranks, AIJ: the same */
  if (done) { /* assembled, with global indices: no local-to-global map (DMGetLocalToGlobalMapping() scans every mesh point) */
    PetscCall(MatSetOption(*K, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_TRUE));
    PetscCall(PetscLogEventEnd(ASSEMBLY_P1_Preallocate, dm, 0, 0, 0));
  } else {
    PetscCall(DMGetLocalToGlobalMapping(dm, &ltog)); /* as DMCreateMatrix() gives it, for any other type (MATIS needs it) */
    PetscCall(AssemblyP1CreateAnyMatrix(dm, in->material, nlocal, bs, vidx, cverts, ltog, K));
  }
  PetscCall(MatSetDM(*K, dm));
  PetscCall(PetscFree(vidx));
  PetscCall(PetscFree(cverts));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* -assembly_check: assembles K both ways (locX: the local solution the FE Jacobian is evaluated at) and prints
   ||K_p1 - K_fe||_F / ||K_fe||_F with the type, block size and number of nonzeros of both. PetscFE's Jacobian needs no
   context: its kernels read constants[] alone. */
PetscErrorCode AssemblyP1Check(DM dm, const AssemblyP1Inputs *in, Vec locX)
{
  MPI_Comm  comm = PetscObjectComm((PetscObject)dm);
  Mat       Kfe, Kp1, D;
  MatInfo   info_fe, info_p1;
  MatType   type_fe, type_p1;
  PetscInt  bs_fe, bs_p1, m_fe, m_p1, n_fe, n_p1;
  PetscReal norm_fe, norm_diff;

  PetscFunctionBeginUser;
  PetscCall(DMCreateMatrix(dm, &Kfe));
  PetscCall(DMPlexSNESComputeJacobianFEM(dm, locX, Kfe, Kfe, NULL));
  PetscCall(MatAssemblyBegin(Kfe, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(Kfe, MAT_FINAL_ASSEMBLY));
  PetscCall(AssemblyP1CreateMatrix(dm, in, &Kp1));
  PetscCall(MatGetType(Kfe, &type_fe));
  PetscCall(MatGetType(Kp1, &type_p1));
  PetscCall(MatGetBlockSize(Kfe, &bs_fe));
  PetscCall(MatGetBlockSize(Kp1, &bs_p1));
  PetscCall(MatGetSize(Kfe, &m_fe, &n_fe));
  PetscCall(MatGetSize(Kp1, &m_p1, &n_p1));
  PetscCall(MatGetInfo(Kfe, MAT_GLOBAL_SUM, &info_fe));
  PetscCall(MatGetInfo(Kp1, MAT_GLOBAL_SUM, &info_p1));
  PetscCall(AssemblyP1CSRAllocated(Kp1, &info_p1.nz_allocated)); /* PETSc reports 0 for a matrix on given arrays */
  PetscCall(MatNorm(Kfe, NORM_FROBENIUS, &norm_fe));
  PetscCall(MatDuplicate(Kfe, MAT_COPY_VALUES, &D));
  PetscCall(MatAXPY(D, -1.0, Kp1, DIFFERENT_NONZERO_PATTERN));
  PetscCall(MatNorm(D, NORM_FROBENIUS, &norm_diff));
  PetscCall(PetscPrintf(comm,
                        "  assembly check: ||K_p1 - K_fe||_F/||K_fe||_F = %.3e; size %" PetscInt_FMT "x%" PetscInt_FMT " (p1) %" PetscInt_FMT
                        "x%" PetscInt_FMT " (fe); type %s (p1) %s (fe); block size %" PetscInt_FMT " (p1) %" PetscInt_FMT
                        " (fe); nonzeros %.0f (p1) %.0f (fe); allocated %.0f (p1) %.0f (fe)\n",
                        (double)(norm_diff / norm_fe), m_p1, n_p1, m_fe, n_fe, type_p1, type_fe, bs_p1, bs_fe, (double)info_p1.nz_used,
                        (double)info_fe.nz_used, (double)info_p1.nz_allocated, (double)info_fe.nz_allocated));
  PetscCall(MatDestroy(&D));
  PetscCall(MatDestroy(&Kfe));
  PetscCall(MatDestroy(&Kp1));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* lambda[q * (dim + 1) + a]: the P1 basis functions (barycentric coordinates) of the closure-ordered vertices at the
   points of PetscFE's quadrature rule. PETSc's reference simplex has the vertices (-1, -1), (1, -1), (-1, 1) (in 3D
   (-1, -1, -1), (1, -1, -1), (-1, 1, -1), (-1, -1, 1)), and its affine map of a cell sends vertex k to the k-th vertex of
   the cell's closure (x = v0 + J (xi + 1), the columns of J (v_k - v0) / 2): lambda_k = (xi_{k-1} + 1) / 2 for k >= 1. */
static PetscErrorCode AssemblyP1QuadratureBasis(PetscInt dim, PetscQuadrature q, PetscReal **lambda, PetscInt *nq, const PetscReal **w)
{
  PetscInt         qdim, nc;
  const PetscReal *pts;

  PetscFunctionBeginUser;
  PetscCall(PetscQuadratureGetData(q, &qdim, &nc, nq, &pts, w));
  PetscCheck(qdim == dim, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Quadrature of dimension %" PetscInt_FMT " on a mesh of dimension %" PetscInt_FMT, qdim,
             dim);
  PetscCall(PetscMalloc1(*nq * (dim + 1), lambda));
  for (PetscInt i = 0; i < *nq; ++i) {
    (*lambda)[i * (dim + 1)] = 1.0;
    for (PetscInt k = 0; k < dim; ++k) {
      (*lambda)[i * (dim + 1) + k + 1] = 0.5 * (pts[i * dim + k] + 1.0);
      (*lambda)[i * (dim + 1)] -= (*lambda)[i * (dim + 1) + k + 1];
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* locF = the bulk residual at locX (the Dirichlet values inserted, zero elsewhere), as DMPlexSNESComputeResidualFEM()
   gives it for P1 simplices, without PetscFE's all-cell buffers: the lifting K u_D, in closed form, on the cells with a
   fixed component (ElementP1AddFixedCellsStiffness), and the body-force term int f0 . phi_a with the points and weights
   of PetscFE's own rule, on every cell if the problem has a body force. The body-force kernels depend on x only (they
   get u = 0). */
PetscErrorCode AssemblyP1Residual(DM dm, const Material *mat, Vec locX, Vec locF)
{
  PetscDS            ds;
  PetscPointFunc     f0, f1;
  PetscSection       lsec, csec;
  DM                 cdm;
  Vec                coords;
  PetscObject        obj;
  PetscQuadrature    q;
  PetscInt           dim, cStart, cEnd, nconst, nq = 0, uOff[1] = {0}, uOff_x[1] = {0};
  const PetscScalar *constants, *xc;
  PetscScalar       *f, u0[3] = {0, 0, 0}, ux0[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  PetscReal         *lambda = NULL, wref = 0.0;
  const PetscReal   *w = NULL;
  MeshClosure        mc;

  PetscFunctionBeginUser;
  PetscCall(VecZeroEntries(locF));
  PetscCall(ElementP1AddFixedCellsStiffness(dm, mat, locX, locF));
  PetscCall(DMGetDS(dm, &ds));
  PetscCall(PetscDSGetResidual(ds, 0, &f0, &f1));
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  if (!f0 || cEnd == cStart) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(PetscDSGetConstants(ds, &nconst, &constants));
  PetscCall(DMGetLocalSection(dm, &lsec));
  PetscCall(DMGetCoordinateDM(dm, &cdm));
  PetscCall(DMGetLocalSection(cdm, &csec));
  PetscCall(DMGetCoordinatesLocal(dm, &coords));
  PetscCall(DMGetField(dm, 0, NULL, &obj));
  PetscCall(PetscFEGetQuadrature((PetscFE)obj, &q));
  PetscCall(AssemblyP1QuadratureBasis(dim, q, &lambda, &nq, &w));
  PetscCall(MeshClosureCreate(dm, &mc));          /* a closure per cell follows */
  for (PetscInt i = 0; i < nq; ++i) wref += w[i]; /* the volume of the reference cell */
  PetscCall(VecGetArrayRead(coords, &xc));
  PetscCall(VecGetArray(locF, &f));
  for (PetscInt c = cStart; c < cEnd; ++c) {
    PetscInt    nv, off[4];
    PetscReal   X[12], vol, det;
    PetscScalar fe[12];

    PetscCall(ElementP1CellVertices(&mc, csec, lsec, xc, c, X, off, &nv));
    for (PetscInt i = 0; i < nv * dim; ++i) fe[i] = 0.0;
    if (dim == 2)
      det = (X[2] - X[0]) * (X[5] - X[1]) - (X[3] - X[1]) * (X[4] - X[0]);
    else {
      const PetscReal a[3] = {X[3] - X[0], X[4] - X[1], X[5] - X[2]}, b[3] = {X[6] - X[0], X[7] - X[1], X[8] - X[2]},
                      e[3] = {X[9] - X[0], X[10] - X[1], X[11] - X[2]};
      det                  = a[0] * (b[1] * e[2] - b[2] * e[1]) - a[1] * (b[0] * e[2] - b[2] * e[0]) + a[2] * (b[0] * e[1] - b[1] * e[0]);
    }
    vol = PetscAbsReal(det) / (dim == 2 ? 2.0 : 6.0);
    for (PetscInt i = 0; i < nq; ++i) {
      const PetscReal *l     = &lambda[i * (dim + 1)];
      PetscReal        xq[3] = {0, 0, 0};
      PetscScalar      f0q[3];

      for (PetscInt a = 0; a < nv; ++a)
        for (PetscInt d = 0; d < dim; ++d) xq[d] += l[a] * X[a * dim + d];
      f0(dim, 1, 0, uOff, uOff_x, u0, NULL, ux0, NULL, NULL, NULL, NULL, NULL, 0.0, xq, nconst, constants, f0q);
      for (PetscInt a = 0; a < nv; ++a)
        for (PetscInt d = 0; d < dim; ++d) fe[a * dim + d] += w[i] * vol / wref * f0q[d] * l[a];
    }
    for (PetscInt a = 0; a < nv; ++a)
      for (PetscInt d = 0; d < dim; ++d) f[off[a] + d] += fe[a * dim + d];
  }
  PetscCall(VecRestoreArray(locF, &f));
  PetscCall(VecRestoreArrayRead(coords, &xc));
  PetscCall(MeshClosureDestroy(&mc));
  PetscCall(PetscFree(lambda));
  PetscFunctionReturn(PETSC_SUCCESS);
}

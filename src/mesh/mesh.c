/* Mesh creation: PETSc's box and file readers, plus the project's simplex box generator. */
#define _DEFAULT_SOURCE /* sysconf(_SC_PHYS_PAGES) */
#include <unistd.h>
#include <petscsf.h>
#include "app.h"
#include "mesh.h"

/* Refuses, before anything is allocated, a mesh of ncells cells (after all refinements) that 32-bit PETSc indices
   cannot number or that needs more memory than the machines of the run have: at least 1 kB per cell (less than the
   cheapest run, linear elasticity with GAMG in 2D, needs), against the physical memory of the nodes. */
PetscErrorCode MeshCheckSize(MPI_Comm comm, PetscInt dim, PetscReal ncells, const char what[])
{
  const PetscReal bytes_per_cell = 1000.0, points_per_cell = dim == 2 ? 3.0 : 4.5; /* cells, faces, edges, vertices */
  PetscReal       memory = 0.0, local;
  MPI_Comm        node;
  PetscMPIInt     node_rank;

  PetscFunctionBeginUser;
  PetscCheck(ncells * points_per_cell < (PetscReal)PETSC_MAX_INT, comm, PETSC_ERR_USER_INPUT,
             "%s: the mesh would have %.3g cells, more mesh points than PETSc's %d-bit indices can number", what, (double)ncells,
             (int)(8 * sizeof(PetscInt)));
  PetscCallMPI(MPI_Comm_split_type(comm, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &node));
  PetscCallMPI(MPI_Comm_rank(node, &node_rank));
  PetscCallMPI(MPI_Comm_free(&node));
  local = node_rank == 0 ? (PetscReal)sysconf(_SC_PHYS_PAGES) * (PetscReal)sysconf(_SC_PAGE_SIZE) : 0.0; /* once per node */
  PetscCall(MPIU_Allreduce(&local, &memory, 1, MPIU_REAL, MPIU_SUM, comm));
  PetscCheck(memory <= 0.0 || ncells * bytes_per_cell <= memory, comm, PETSC_ERR_USER_INPUT,
             "%s: the mesh would have %.3g cells and need at least %.3g GB of memory, more than the %.3g GB of the machine(s) of this run", what,
             (double)ncells, (double)(ncells * bytes_per_cell / 1e9), (double)(memory / 1e9));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Reads the mesh file, with an error that names the file and the reader's complaint. */
static PetscErrorCode MeshReadFile(MPI_Comm comm, const char filename[], DM *dm)
{
  PetscErrorCode ierr;

  PetscFunctionBeginUser;
  PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
  ierr = DMPlexCreateFromFile(comm, filename, "", PETSC_TRUE, dm);
  PetscCall(PetscPopErrorHandler());
  if (ierr) {
    const char *text     = NULL;
    char       *specific = NULL;

    PetscCall(PetscErrorMessage(ierr, &text, &specific));
    SETERRQ(PETSC_COMM_SELF, PETSC_ERR_FILE_READ, "Cannot read the mesh file '%s' (-dm_plex_filename): %s", filename,
            specific && specific[0] ? specific : text);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Creates the mesh from PETSc's own options; simplex boxes, which PETSc 3.18 cannot generate
   without Triangle/CTetGen, come from MeshCreateSimplexBox(). later_refinements: uniform refinements the run will
   still make (grid sequencing), counted in the size check. coarse_requests: in 2D and in 3D, nested iteration to the box of the options
   (-1: as many levels as keep coarse_faces[dim - 2] cells per side, and at least coarse_min_levels while the box has 2 cells per
   side to halve, where the box nests, and in 3D none where the coarsest box would keep more than coarse_faces[2] (if > 0); 0: none; k: k levels, or
   an error): the box built is then the coarsest, and box->coarse_levels says how many doublings lead to the one asked for. */
PetscErrorCode MeshCreate(MPI_Comm comm, PetscInt later_refinements, const PetscInt coarse_requests[2], const PetscInt coarse_faces[3],
                          PetscInt coarse_min_levels, MeshBox *box, DM *dm)
{
  PetscInt  dim, faces[3], nfaces = 3, nlower = 3, nupper = 3, refine, curved_ridges = 0;
  PetscReal curved_x[3] = {0, 0, 0};
  PetscReal lower[3] = {0.0, 0.0, 0.0}, upper[3] = {1.0, 1.0, 1.0};
  PetscBool simplex, has_file, dim_set, nests, parallel_read = PETSC_FALSE, petsc_interpolate, check_interpolation, check_closures, petsc_read;
  char      filename[PETSC_MAX_PATH_LEN] = "";
  MeshPartitionerType partitioner;
  PetscMPIInt         size;
  PetscInt            coarse = 0, coarse_request, slab_rows = 0;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscOptionsBegin(comm, NULL, "Mesh options (PETSc's names, and -partitioner)", "DMPLEX");
  PetscCall(PetscOptionsString("-dm_plex_filename", "Mesh file (Gmsh, ExodusII, HDF5)", "DMPlexCreateFromFile", filename, filename, sizeof(filename),
                               &has_file));
  dim = 2;
  PetscCall(PetscOptionsRangeInt("-dm_plex_dim", "Dimension of the box mesh", "DMPlexCreateBoxMesh", dim, &dim, &dim_set, 2, 3));
  simplex = PETSC_TRUE;
  PetscCall(PetscOptionsBool("-dm_plex_simplex", "Simplices (triangles, tetrahedra) or tensor cells (quads, hexes)", "DMPlexCreateBoxMesh", simplex,
                             &simplex, NULL));
  faces[0] = faces[1] = faces[2] = (dim == 2) ? 8 : 4;
  PetscCall(PetscOptionsIntArray("-dm_plex_box_faces", "Number of cells along each side of the box", "DMPlexCreateBoxMesh", faces, &nfaces, NULL));
  PetscCall(PetscOptionsRealArray("-dm_plex_box_lower", "Lower corner of the box", "DMPlexCreateBoxMesh", lower, &nlower, NULL));
  PetscCall(PetscOptionsRealArray("-dm_plex_box_upper", "Upper corner of the box", "DMPlexCreateBoxMesh", upper, &nupper, NULL));
  /* the project's simplex box is built distributed; anything else is distributed by METIS, which gives the same
     partition on every run of a command: PTScotch (PETSc 3.18's default here) may partition the same mesh
     differently from run to run, and with the partition the iteration counts, the final residual and, on hard
     problems, whether the run converges (issue 29) */
  partitioner = !has_file && simplex ? MESH_PARTITIONER_BOX : MESH_PARTITIONER_METIS;
  PetscCall(PetscOptionsEnum("-partitioner", "How the cells are distributed over the ranks", "MeshPartitionDistribute", MeshPartitionerTypes,
                             (PetscEnum)partitioner, (PetscEnum *)&partitioner, NULL));
  petsc_interpolate = PETSC_FALSE;
  PetscCall(PetscOptionsBool("-box_petsc_interpolate",
                             "Interpolate the simplex box (faces, edges) with DMPlexInterpolate(), not the project's direct build",
                             "MeshCreateInterpolatedSimplices", petsc_interpolate, &petsc_interpolate, NULL));
  petsc_read = PETSC_FALSE;
  PetscCall(PetscOptionsBool("-mesh_remeshed_petsc_read",
                             "Read each mesh Gmsh makes for the adaptive cycles from the file Gmsh writes, with PETSc's reader and "
                             "DMPlexInterpolate(), not the project's direct build from Gmsh's API (the same mesh, slower)",
                             "MeshSimplicesBuild", petsc_read, &petsc_read, NULL));
  check_interpolation = PETSC_FALSE;
  PetscCall(PetscOptionsBool("-box_interpolation_check", "Build the serial simplex box both ways and print how their topologies differ",
                             "MeshCompareTopology", check_interpolation, &check_interpolation, NULL));
  check_closures = PETSC_FALSE;
  PetscCall(PetscOptionsBool("-mesh_closure_check",
                             "Compare every point's closure and star with DMPlexGetTransitiveClosure() and print the differences", "MeshClosureCheck",
                             check_closures, &check_closures, NULL));
  refine = 0;
  PetscCall(PetscOptionsRangeInt("-dm_refine", "Uniform refinements, after the distribution", "DMRefine", refine, &refine, NULL, 0, 12));
  PetscOptionsEnd();
  PetscCheck(partitioner != MESH_PARTITIONER_BOX || (!has_file && simplex), comm, PETSC_ERR_USER_INPUT,
             "-partitioner box splits the project's simplex box as it builds it; %s needs ptscotch, metis or simple",
             has_file ? "a mesh file (-dm_plex_filename)" : "a tensor box (-dm_plex_simplex 0)");
  PetscCall(OptionsCheckFiniteArray(comm, "-dm_plex_box_lower", dim, lower));
  PetscCall(OptionsCheckFiniteArray(comm, "-dm_plex_box_upper", dim, upper));
  for (PetscInt d = 0; d < dim; ++d) {
    PetscCheck(faces[d] >= 1, comm, PETSC_ERR_USER_INPUT, "-dm_plex_box_faces: need at least one cell per side, got %" PetscInt_FMT, faces[d]);
    PetscCheck(upper[d] > lower[d], comm, PETSC_ERR_USER_INPUT, "-dm_plex_box_upper must exceed -dm_plex_box_lower in every direction");
  }

  if (has_file) {
    PetscBool exists;

    char where[PETSC_MAX_PATH_LEN + 96];

    PetscCall(PetscTestFile(filename, 'r', &exists));
    PetscCall(OptionsPathWhere(filename, where, sizeof(where)));
    PetscCheck(exists, comm, PETSC_ERR_USER_INPUT, "Mesh file '%s' (-dm_plex_filename) does not exist or cannot be read%s", filename, where);
  }
  if (!has_file) {
    char      what[64];
    PetscReal ncells = (simplex ? (dim == 2 ? 2.0 : 6.0) : 1.0) * PetscPowReal(2.0, (PetscReal)(dim * (refine + later_refinements)));

    for (PetscInt d = 0; d < dim; ++d) ncells *= (PetscReal)faces[d];
    PetscCall(PetscSNPrintf(what, sizeof(what), "-dm_plex_box_faces with %" PetscInt_FMT " refinement(s)", refine + later_refinements));
    PetscCall(MeshCheckSize(comm, dim, ncells, what));
  }
  /* the boxes of nested iteration; on several ranks built in slabs of rows. The Kuhn box of 2N cells per side refines
     the Kuhn box of N in 3D too: a Kuhn tetrahedron of the coarse cube is cut by the planes x_i = const and
     x_i - x_j = const of the coarse grid, which are planes of the fine grid's, so it is a union of fine Kuhn tetrahedra
     (checked on 2^3 against 4^3: each of the 384 fine tetrahedra lies in one coarse tetrahedron), and every fine vertex
     is a coarse vertex or the midpoint of a coarse edge (MeshCreateBoxLevel()) */
  coarse_request = coarse_requests[dim - 2];
  nests          = (PetscBool)(!has_file && simplex && refine == 0 && (dim == 2 || dim == 3) && (size == 1 || partitioner == MESH_PARTITIONER_BOX));
  { /* nested iteration to the box of the options: the box built first has 2^coarse times fewer cells per side. On several
       ranks each box is built in slabs of its rows (-partitioner box), every slab boundary a row of the coarsest box (its
       rows split as evenly as whole rows go, at least one a rank), so that the boxes nest rank by rank */
    if (coarse_request > 0) {
      PetscCheck(nests, comm, PETSC_ERR_USER_INPUT,
                 "-contact_coarse_levels %" PetscInt_FMT
                 " needs the simplex box (-dm_plex_box_faces) without -dm_refine, and on several ranks -partitioner box",
                 coarse_request);
      for (PetscInt d = 0; d < dim; ++d)
        PetscCheck(faces[d] % (1 << coarse_request) == 0, comm, PETSC_ERR_USER_INPUT,
                   "-contact_coarse_levels %" PetscInt_FMT ": -dm_plex_box_faces %" PetscInt_FMT " is not divisible by 2^%" PetscInt_FMT,
                   coarse_request, faces[d], coarse_request);
      PetscCheck((faces[dim - 1] >> coarse_request) >= size, comm, PETSC_ERR_USER_INPUT,
                 "-contact_coarse_levels %" PetscInt_FMT " on %d ranks: the coarsest box's %" PetscInt_FMT " rows are fewer than the ranks",
                 coarse_request, (int)size, faces[dim - 1] >> coarse_request);
      coarse = coarse_request;
    } else if (coarse_request < 0 && nests) {
      /* halvings while the rows split evenly over the ranks (each rank's slabs as many rows); in 3D, where the coarsest
         box would then be too large to factor, and where -bars needs its coarser boxes (16 x 16 on 3 ranks: 8 rows do
         not split evenly, 4 uneven rows of 4 x 4 do), halvings into uneven whole rows (68^3 on 2 ranks: 17^3 in slabs of 8 and
         9 rows, the final box's of 32 and 36, rather than 34^3 or no nesting; docs/decisions.md, "Uneven slabs") */
      for (PetscInt pass = 0; pass < 2; ++pass) {
        const PetscBool even = (PetscBool)(pass == 0);

        coarse = 0;
        for (PetscBool halves = PETSC_TRUE; halves && coarse < 8;) {
          const PetscInt rows = faces[dim - 1] >> (coarse + 1);

          halves = (PetscBool)(even ? rows % size == 0 : rows >= size);
          for (PetscInt d = 0; d < dim; ++d)
            halves = (PetscBool)(halves && faces[d] % (2 << coarse) == 0 &&
                                 faces[d] >> (coarse + 1) >= (coarse < coarse_min_levels ? 2 : coarse_faces[dim - 2]));
          if (halves) ++coarse;
        }
        if (dim == 3 && coarse_faces[2] > 0 && coarse >= coarse_min_levels)
          for (PetscInt d = 0; d < dim; ++d)
            if (faces[d] >> coarse > coarse_faces[2]) coarse = 0; /* its factorization would be dear */
        if (coarse >= coarse_min_levels && (coarse > 0 || dim != 3 || size == 1)) break;
      }
    }
    for (PetscInt d = 0; d < dim; ++d) faces[d] >>= coarse;
    /* several ranks: whole rows of this box on each rank where it is the coarsest of nested iteration, or where its rows
       divide by the ranks (the same slabs as the even split of its cells, whose finer boxes nest in them too) */
    if (size > 1 && nests && (coarse > 0 || faces[dim - 1] % size == 0)) slab_rows = faces[dim - 1];
  }
  /* The serial mesh on rank 0 (a file, the project's simplex box, PETSc's tensor box), distributed by
     MeshPartitionDistribute() with the partitioner of -partitioner; PETSc's own DM options are applied to the
     distributed mesh last (DMSetFromOptions()), so that -dm_refine refines it on all ranks, not the whole mesh on
     rank 0 before its distribution. PETSc reads HDF5 meshes in parallel, in pieces that are only consistent after its
     own distribution (without it the solution is wrong): they get both. */
  if (has_file) {
    PetscInt  fdim, cStart, cEnd, n;
    PetscReal ncells;
    char      what[PETSC_MAX_PATH_LEN + 64];

    PetscCall(PetscStrendswith(filename, ".h5", &parallel_read));
    PetscCheck(!parallel_read || strlen(filename) <= 240, comm, PETSC_ERR_USER_INPUT,
               "The HDF5 mesh file name '%s' (-dm_plex_filename) has %d characters: PETSc reads it with MPI-IO, which in Open MPI 4.1 crashes on "
               "names of more than 240; use a shorter (for example relative) path",
               filename, (int)strlen(filename));
    PetscCall(MeshReadFile(comm, filename, dm));
    PetscCall(MeshCheckFile(*dm, filename)); /* one cell type, first order, no cell twice: before anything is assembled */
    {
      PetscBool gmsh;

      PetscCall(PetscStrendswith(filename, ".msh", &gmsh));
      if (gmsh) PetscCall(MeshLabelGmshNames(*dm, filename)); /* the physical groups' names, for the boundary options */
    }
    PetscCall(DMGetDimension(*dm, &fdim));
    PetscCheck(!dim_set || fdim == dim, comm, PETSC_ERR_USER_INPUT,
               "The mesh file '%s' holds a %" PetscInt_FMT "D mesh, but -dm_plex_dim %" PetscInt_FMT " was given", filename, fdim, dim);
    PetscCall(DMPlexGetHeightStratum(*dm, 0, &cStart, &cEnd));
    n = cEnd - cStart;
    PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &n, 1, MPIU_INT, MPI_SUM, comm)); /* the cells of the file (before the distribution) */
    ncells = (PetscReal)n * PetscPowReal(2.0, (PetscReal)(fdim * (refine + later_refinements)));
    PetscCall(PetscSNPrintf(what, sizeof(what), "%s with %" PetscInt_FMT " refinement(s)", filename, refine + later_refinements));
    PetscCall(MeshCheckSize(comm, fdim, ncells, what));
    if (parallel_read) {
      DM dist = NULL;

      PetscCall(DMPlexDistribute(*dm, 0, NULL, &dist));
      if (dist) {
        PetscCall(DMDestroy(dm));
        *dm = dist;
      }
    }
    {
      PetscInt nreflected, ncells_all;

      PetscCall(MeshOrientCells(*dm, filename, &nreflected)); /* cells listed clockwise reflected (mesh_orient.c), before any integral */
      PetscCall(DMPlexGetHeightStratum(*dm, 0, &cStart, &cEnd));
      ncells_all = cEnd - cStart;
      PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &ncells_all, 1, MPIU_INT, MPI_SUM, comm));
      if (nreflected)
        PetscCall(PetscPrintf(comm,
                              "  mesh: %" PetscInt_FMT " of the %" PetscInt_FMT
                              " cells of %s are listed with the reversed orientation (clockwise in 2D); each was reflected to det J > 0\n",
                              nreflected, ncells_all, filename));
    }
    PetscCall(
        MeshCountCurvedRidges(*dm, &curved_ridges, curved_x)); /* the file's own boundary before any refinement (a parallel read: once consistent) */
  } else if (simplex)
    PetscCall(MeshCreateSimplexBox(comm, dim, faces, lower, upper, (PetscBool)(partitioner == MESH_PARTITIONER_BOX), slab_rows, petsc_interpolate,
                                   check_interpolation, dm));
  else
    PetscCall(CompatCreateBoxMesh(comm, dim, PETSC_FALSE, faces, lower, upper, NULL, PETSC_TRUE, dm));
  {
    PetscCall(PetscMemzero(box, sizeof(*box)));
    box->is_box        = (PetscBool)(nests && (size == 1 || slab_rows > 0)); /* several ranks: slabs of rows of this box nest in the finer boxes' */
    box->slab_rows     = slab_rows;
    box->coarse_levels = coarse;
    box->dim           = dim;
    box->from_file     = has_file;
    box->refine        = refine;
    box->curved_ridges = curved_ridges;
    box->petsc_read    = petsc_read;
    for (PetscInt d = 0; d < 3; ++d) box->curved_x[d] = curved_x[d];
    for (PetscInt d = 0; d < dim; ++d) {
      box->faces[d] = faces[d];
      box->lower[d] = lower[d];
      box->upper[d] = upper[d];
    }
  }
  PetscCall(MeshPartitionDistribute(partitioner, dm));
  PetscCall(DMPlexDistributeSetDefault(*dm, PETSC_FALSE));
  PetscCall(DMSetFromOptions(*dm)); /* -dm_refine on all ranks, -dm_mat_type, PETSc's checks */
  PetscCall(PetscObjectSetName((PetscObject)*dm, "mesh"));
  PetscCall(DMViewFromOptions(*dm, NULL, "-dm_view"));
  if (check_closures) {
    PetscInt  counts[3], pStart, pEnd;
    PetscBool by_depth;

    PetscCall(MeshClosureCheck(*dm, &counts[0], &by_depth));
    PetscCall(DMPlexGetChart(*dm, &pStart, &pEnd));
    counts[1] = 2 * (pEnd - pStart);
    counts[2] = by_depth ? 1 : 0;
    PetscCall(MPIU_Allreduce(MPI_IN_PLACE, counts, 3, MPIU_INT, MPI_SUM, comm));
    PetscCall(PetscPrintf(comm,
                          "  closure check: %" PetscInt_FMT " differences from DMPlexGetTransitiveClosure() in %" PetscInt_FMT
                          " closures and stars; walk by depth on %" PetscInt_FMT " rank(s)\n",
                          counts[0], counts[1], counts[2]));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The file Gmsh wrote for the run (mesh_remesh.c, -mesh_remeshed_petsc_read), read by PETSc's reader with its physical
   groups' names: the reference that the direct build (mesh_gmsh_build.c) is compared to. */
PetscErrorCode MeshReadRemeshedFile(MPI_Comm comm, const char filename[], DM *dm)
{
  PetscFunctionBeginUser;
  PetscCall(MeshReadFile(comm, filename, dm));
  PetscCall(MeshLabelGmshNames(*dm, filename));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* A mesh Gmsh made for the run (mesh_remesh.c), serial on rank 0: checked as a mesh file is and distributed by METIS. */
PetscErrorCode MeshDistributeRemeshed(const char what[], DM *dm)
{
  PetscFunctionBeginUser;
  PetscInt nreflected;

  PetscCall(MeshCheckFile(*dm, what));
  PetscCall(MeshOrientCells(*dm, what, &nreflected)); /* a model whose surfaces turn clockwise gives clockwise cells */
  PetscCall(MeshPartitionDistribute(MESH_PARTITIONER_METIS, dm));
  PetscCall(DMPlexDistributeSetDefault(*dm, PETSC_FALSE));
  PetscCall(PetscObjectSetName((PetscObject)*dm, "mesh"));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* PETSc 3.18 looks a point's cell type up in the "celltype" label (DMPlexGetCellType(), called for every point of every
   DMPlexGetTransitiveClosure()). Its DMPlexGetGhostCellStratum(), which the section's creation and the insertion of
   Dirichlet values call, turns every stratum of that label into a hash set after reading it: a lookup then queries a
   hash set, slower than a search of the sorted (here contiguous) lists PETSc makes of them on request. This asks for
   each stratum, so that the closure loops that follow get the fast lookup. The label's content is unchanged. */
PetscErrorCode MeshIndexCellTypes(DM dm)
{
  DMLabel         label;
  IS              values;
  const PetscInt *vals;
  PetscInt        nvalues;

  PetscFunctionBeginUser;
  PetscCall(DMPlexGetCellTypeLabel(dm, &label));
  PetscCall(DMLabelGetValueIS(label, &values));
  PetscCall(ISGetLocalSize(values, &nvalues));
  PetscCall(ISGetIndices(values, &vals));
  for (PetscInt v = 0; v < nvalues; ++v) {
    IS points;

    PetscCall(DMLabelGetStratumIS(label, vals[v], &points)); /* makes the stratum a sorted list */
    PetscCall(ISDestroy(&points));
  }
  PetscCall(ISRestoreIndices(values, &vals));
  PetscCall(ISDestroy(&values));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The largest and the mean distance between two vertices of cell c (its diameter, and for a simplex its mean edge). */
static PetscErrorCode VertexDistances(DM dm, PetscInt c, PetscReal *largest, PetscReal *mean)
{
  DM           cdm;
  PetscSection csection;
  Vec          coords;
  PetscInt     cdim, n, npairs = 0;
  PetscScalar *x   = NULL;
  PetscReal    sum = 0.0;

  PetscFunctionBeginUser;
  PetscCall(DMGetCoordinateDim(dm, &cdim));
  PetscCall(DMGetCoordinateDM(dm, &cdm));
  PetscCall(DMGetLocalSection(cdm, &csection));
  PetscCall(DMGetCoordinatesLocal(dm, &coords));
  *largest = 0.0;
  PetscCall(DMPlexVecGetClosure(cdm, csection, coords, c, &n, &x));
  for (PetscInt i = 0; i < n / cdim; ++i)
    for (PetscInt j = i + 1; j < n / cdim; ++j, ++npairs) {
      PetscReal d2 = 0.0;
      for (PetscInt d = 0; d < cdim; ++d) d2 += PetscSqr(PetscRealPart(x[i * cdim + d] - x[j * cdim + d]));
      *largest = PetscMax(*largest, PetscSqrtReal(d2));
      sum += PetscSqrtReal(d2);
    }
  PetscCall(DMPlexVecRestoreClosure(cdm, csection, coords, c, &n, &x));
  *mean = npairs ? sum / npairs : 0.0;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The diameter of cell c: the largest distance between two of its vertices. */
PetscErrorCode MeshCellDiameter(DM dm, PetscInt c, PetscReal *diam)
{
  PetscReal mean;

  PetscFunctionBeginUser;
  PetscCall(VertexDistances(dm, c, diam, &mean));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The mean edge length of simplex c (the size Gmsh is asked for, MeshRemesh()). */
PetscErrorCode MeshCellMeanEdge(DM dm, PetscInt c, PetscReal *mean)
{
  PetscReal largest;

  PetscFunctionBeginUser;
  PetscCall(VertexDistances(dm, c, &largest, mean));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The sizes MeshSetCellSizes() kept with dm, or *sizes = NULL. */
static PetscErrorCode MeshGetCellSizes(DM dm, PetscReal *hmax, const PetscReal **sizes)
{
  PetscContainer container;
  PetscInt       cStart, cEnd;

  PetscFunctionBeginUser;
  *sizes = NULL;
  PetscCall(PetscObjectQuery((PetscObject)dm, "eps_cell_size", (PetscObject *)&container));
  if (!container) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscContainerGetPointer(container, (void **)sizes));
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  *hmax = (*sizes)[cEnd - cStart];
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The size of cell c that the penalty's eps follows (eps = eps0 h^power / M): its diameter, unless the mesh carries
   sizes of its own (MeshSetCellSizes(): the error bars' coarser levels of a tetrahedral mesh, src/drivers/grid_sequence.c). */
PetscErrorCode MeshCellSize(DM dm, PetscInt c, PetscReal *h)
{
  const PetscReal *sizes;
  PetscReal        hmax;
  PetscInt         cStart;

  PetscFunctionBeginUser;
  PetscCall(MeshGetCellSizes(dm, &hmax, &sizes));
  if (sizes) {
    PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, NULL));
    *h = sizes[c - cStart];
  } else
    PetscCall(MeshCellDiameter(dm, c, h));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The h of eps = eps0 h^power / M on this mesh: diameter_max (the caller's MeshGetMaxCellDiameter()), or the largest of
   the mesh's own sizes. */
PetscErrorCode MeshGetMaxCellSize(DM dm, PetscReal diameter_max, PetscReal *h)
{
  const PetscReal *sizes;

  PetscFunctionBeginUser;
  PetscCall(MeshGetCellSizes(dm, h, &sizes));
  if (!sizes) *h = diameter_max;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Keeps with dm (a container composed on it) one size per local cell, sizes[c - cStart] (taken over: freed with dm), and
   the global largest one, hmax, in the array's last entry. */
PetscErrorCode MeshSetCellSizes(DM dm, PetscReal hmax, PetscReal *sizes)
{
  PetscContainer container;
  PetscInt       cStart, cEnd;

  PetscFunctionBeginUser;
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  sizes[cEnd - cStart] = hmax; /* the array has one more entry */
  PetscCall(PetscContainerCreate(PetscObjectComm((PetscObject)dm), &container));
  PetscCall(PetscContainerSetPointer(container, sizes));
  PetscCall(PetscContainerSetUserDestroy(container, PetscContainerUserDestroyDefault));
  PetscCall(PetscObjectCompose((PetscObject)dm, "eps_cell_size", (PetscObject)container));
  PetscCall(PetscContainerDestroy(&container));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* h: the largest cell diameter (largest distance between two vertices of a cell) over all ranks. The diameter of a
   simplex is its longest edge: on an interpolated simplex mesh the edges are visited once, not the closure of every
   cell. */
PetscErrorCode MeshGetMaxCellDiameter(DM dm, PetscReal *h)
{
  DM           cdm;
  PetscSection csection;
  Vec          coords;
  PetscInt     cStart, cEnd, cdim, depth, dim;
  PetscReal    hmax = 0.0;
  PetscBool    simplex;

  PetscFunctionBeginUser;
  PetscCall(DMGetCoordinateDim(dm, &cdim));
  PetscCall(DMGetCoordinateDM(dm, &cdm));
  PetscCall(DMGetLocalSection(cdm, &csection));
  PetscCall(DMGetCoordinatesLocal(dm, &coords));
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  PetscCall(DMPlexGetDepth(dm, &depth));
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMPlexIsSimplex(dm, &simplex));
  if (simplex && depth == dim && cEnd > cStart) {
    const PetscScalar *x;
    PetscInt           eStart, eEnd;

    PetscCall(DMPlexGetDepthStratum(dm, 1, &eStart, &eEnd));
    PetscCall(VecGetArrayRead(coords, &x));
    for (PetscInt e = eStart; e < eEnd; ++e) {
      const PetscInt *cone;
      PetscInt        o0, o1;
      PetscReal       d2 = 0.0;

      PetscCall(DMPlexGetCone(dm, e, &cone));
      PetscCall(PetscSectionGetOffset(csection, cone[0], &o0));
      PetscCall(PetscSectionGetOffset(csection, cone[1], &o1));
      for (PetscInt d = 0; d < cdim; ++d) d2 += PetscSqr(PetscRealPart(x[o0 + d] - x[o1 + d]));
      hmax = PetscMax(hmax, PetscSqrtReal(d2));
    }
    PetscCall(VecRestoreArrayRead(coords, &x));
    PetscCall(MPIU_Allreduce(&hmax, h, 1, MPIU_REAL, MPIU_MAX, PetscObjectComm((PetscObject)dm)));
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  for (PetscInt c = cStart; c < cEnd; ++c) {
    PetscScalar *x = NULL;
    PetscInt     n;

    PetscCall(DMPlexVecGetClosure(cdm, csection, coords, c, &n, &x));
    for (PetscInt i = 0; i < n / cdim; ++i)
      for (PetscInt j = i + 1; j < n / cdim; ++j) {
        PetscReal d2 = 0.0;
        for (PetscInt d = 0; d < cdim; ++d) d2 += PetscSqr(PetscRealPart(x[i * cdim + d] - x[j * cdim + d]));
        hmax = PetscMax(hmax, PetscSqrtReal(d2));
      }
    PetscCall(DMPlexVecRestoreClosure(cdm, csection, coords, c, &n, &x));
  }
  PetscCall(MPIU_Allreduce(&hmax, h, 1, MPIU_REAL, MPIU_MAX, PetscObjectComm((PetscObject)dm)));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Refuses a mesh whose "Face Sets" label has no face with the value of Gamma_C. */
PetscErrorCode MeshCheckContactBoundary(DM dm, PetscInt contact_id)
{
  MPI_Comm comm = PetscObjectComm((PetscObject)dm);
  DMLabel  label;
  PetscInt n, ntotal, *faces;

  PetscFunctionBeginUser;
  PetscCall(DMGetLabel(dm, "Face Sets", &label));
  PetscCheck(label, comm, PETSC_ERR_USER_INPUT,
             "The mesh has no \"Face Sets\" label, so it has no contact boundary Gamma_C (Face Sets value %" PetscInt_FMT ")", contact_id);
  PetscCall(MeshGetBoundaryFaces(dm, contact_id, &n, &faces));
  PetscCall(PetscFree(faces));
  PetscCall(MPIU_Allreduce(&n, &ntotal, 1, MPIU_INT, MPI_SUM, comm));
  PetscCheck(ntotal > 0, comm, PETSC_ERR_USER_INPUT,
             "The mesh has no contact boundary: no face carries \"Face Sets\" value %" PetscInt_FMT " (Gamma_C)", contact_id);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Number of points of a stratum owned by this rank, summed over ranks. */
PetscErrorCode MeshCountOwned(DM dm, PetscInt pStart, PetscInt pEnd, PetscInt *count)
{
  PetscSF         sf;
  PetscInt        nleaves, n = 0;
  const PetscInt *leaves;

  PetscFunctionBeginUser;
  PetscCall(DMGetPointSF(dm, &sf));
  PetscCall(PetscSFGetGraph(sf, NULL, &nleaves, &leaves, NULL));
  n = pEnd - pStart;
  if (nleaves > 0 && leaves)
    for (PetscInt l = 0; l < nleaves; ++l) n -= (leaves[l] >= pStart && leaves[l] < pEnd);
  PetscCall(MPIU_Allreduce(&n, count, 1, MPIU_INT, MPI_SUM, PetscObjectComm((PetscObject)dm)));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The index of each point of [pStart, pEnd) of this rank among those it owns (in point order: for the vertices, the
   order of /geometry/vertices), -1 for a point another rank owns (a leaf of the point SF); the caller frees index. */
PetscErrorCode MeshOwnedIndex(DM dm, PetscInt pStart, PetscInt pEnd, PetscInt **index, PetscInt *nowned)
{
  PetscSF         sf;
  PetscInt        nleaves;
  const PetscInt *ilocal;

  PetscFunctionBeginUser;
  PetscCall(PetscCalloc1(pEnd - pStart, index));
  PetscCall(DMGetPointSF(dm, &sf));
  PetscCall(PetscSFGetGraph(sf, NULL, &nleaves, &ilocal, NULL));
  for (PetscInt l = 0; l < PetscMax(nleaves, 0); ++l) {
    const PetscInt p = ilocal ? ilocal[l] : l;

    if (p >= pStart && p < pEnd) (*index)[p - pStart] = -1;
  }
  *nowned = 0;
  for (PetscInt i = 0; i < pEnd - pStart; ++i)
    if ((*index)[i] == 0) (*index)[i] = (*nowned)++; /* 0: not a leaf, owned */
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The faces of dm with "Face Sets" value id (local, height 1), in a new array the caller frees with PetscFree(). */
PetscErrorCode MeshGetBoundaryFaces(DM dm, PetscInt id, PetscInt *n, PetscInt **faces)
{
  DMLabel  label;
  IS       is = NULL;
  PetscInt fStart, fEnd;

  PetscFunctionBeginUser;
  *n = 0;
  PetscCall(DMGetLabel(dm, "Face Sets", &label));
  if (label) PetscCall(DMLabelGetStratumIS(label, id, &is));
  PetscCall(DMPlexGetHeightStratum(dm, 1, &fStart, &fEnd));
  if (is) {
    const PetscInt *points;
    PetscInt        np;

    PetscCall(ISGetLocalSize(is, &np));
    PetscCall(ISGetIndices(is, &points));
    PetscCall(PetscMalloc1(np, faces));
    for (PetscInt i = 0; i < np; ++i)
      if (points[i] >= fStart && points[i] < fEnd) (*faces)[(*n)++] = points[i];
    PetscCall(ISRestoreIndices(is, &points));
    PetscCall(ISDestroy(&is));
  } else
    PetscCall(PetscMalloc1(1, faces));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The global index of each of the dim components of point p, as DMPlex's closure indices give them: -1 for a
   constrained component, otherwise the point's offset in the global section (the owner's, for a ghost) plus the free
   components before it. lsec holds the constraints, gsec the global offsets. */
PetscErrorCode MeshPointGlobalIndices(PetscSection lsec, PetscSection gsec, PetscInt p, PetscInt dim, PetscInt idx[])
{
  const PetscInt *cind = NULL;
  PetscInt        off, cdof, k = 0;

  PetscFunctionBeginUser;
  PetscCall(PetscSectionGetOffset(gsec, p, &off));
  PetscCall(PetscSectionGetConstraintDof(lsec, p, &cdof));
  if (cdof) PetscCall(PetscSectionGetConstraintIndices(lsec, p, &cind));
  off = off < 0 ? -(off + 1) : off;
  for (PetscInt c = 0; c < dim; ++c) {
    if (k < cdof && cind[k] == c) {
      idx[c] = -1;
      ++k;
    } else
      idx[c] = off + c - k;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* One size for every cell, the smallest diameter of the cells with a face on Gamma_C (the face sets ids[]): the
   penalty's eps is then one value over Gamma_C, eps = eps0 h_C^power / M, as the adaptive refinement needs
   (src/drivers/adapt.c). A local eps that follows each contact face's size jumps by 2 where a refined face meets an
   unrefined one; the penalty's stiffness 1/eps jumps with it, which the continuous P1 displacement cannot follow, and
   the nodal pressure oscillates from node to node (docs/estimate.md, "Adaptive refinement"). */
PetscErrorCode MeshSetContactCellSizes(DM dm, PetscInt nids, const PetscInt ids[])
{
  PetscInt  cStart, cEnd;
  PetscReal h = PETSC_MAX_REAL, *sizes;

  PetscFunctionBeginUser;
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  for (PetscInt k = 0; k < nids; ++k) {
    PetscInt *faces, n;

    PetscCall(MeshGetBoundaryFaces(dm, ids[k], &n, &faces));
    for (PetscInt f = 0; f < n; ++f) {
      const PetscInt *support;
      PetscInt        ns;

      PetscCall(DMPlexGetSupportSize(dm, faces[f], &ns));
      PetscCall(DMPlexGetSupport(dm, faces[f], &support));
      for (PetscInt s = 0; s < ns; ++s) {
        PetscReal diam;

        if (support[s] < cStart || support[s] >= cEnd) continue;
        PetscCall(MeshCellDiameter(dm, support[s], &diam));
        h = PetscMin(h, diam);
      }
    }
    PetscCall(PetscFree(faces));
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &h, 1, MPIU_REAL, MPIU_MIN, PetscObjectComm((PetscObject)dm)));
  PetscCheck(h < PETSC_MAX_REAL, PetscObjectComm((PetscObject)dm), PETSC_ERR_USER_INPUT, "the mesh has no cell on the contact boundary");
  PetscCall(PetscMalloc1(cEnd - cStart + 1, &sizes));
  for (PetscInt c = 0; c < cEnd - cStart; ++c) sizes[c] = h;
  PetscCall(MeshSetCellSizes(dm, h, sizes));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The mesh file's part of /run: the ridges of its curved boundary that MeshCountCurvedRidges() found (nothing for a box). */
PetscErrorCode MeshBoxWrite(const MeshBox *box, PetscViewer v)
{
  PetscFunctionBeginUser;
  if (box->from_file) PetscCall(RunAttrInt(v, box->curved_ridges, "curved_boundary_ridges"));
  PetscFunctionReturn(PETSC_SUCCESS);
}

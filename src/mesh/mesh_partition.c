/* Distribution of the serial mesh over the ranks with a chosen partitioner (-partitioner), and the quality of
   the partition: edge cut and load imbalance. METIS is called directly on the cell dual graph and its result
   handed to PETSc through a shell partitioner (PETSc 3.18 here is built without METIS/ParMETIS). */
#include <metis.h>
#include <petscsf.h>
#include "mesh.h"
#include "app.h"

const char *const MeshPartitionerTypes[] = {"ptscotch", "metis", "simple", "box", "MeshPartitionerType", "MESH_PARTITIONER_", NULL};

#define MESH_PARTITION_STATS_KEY "MeshPartitionStats"

/* Number of cells on each rank above rank 0, summed: 0 when the mesh lies entirely on rank 0. */
static PetscErrorCode MeshPartitionCellsOffRoot(DM dm, PetscInt *n)
{
  PetscInt    cStart, cEnd, nlocal;
  PetscMPIInt rank;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(PetscObjectComm((PetscObject)dm), &rank));
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  nlocal = rank ? cEnd - cStart : 0;
  PetscCall(MPIU_Allreduce(&nlocal, n, 1, MPIU_INT, MPI_SUM, PetscObjectComm((PetscObject)dm)));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Distributes *dm with part (overlap 0) and replaces *dm by the distributed mesh. */
static PetscErrorCode MeshPartitionApply(PetscPartitioner part, DM *dm)
{
  DM dist = NULL;

  PetscFunctionBeginUser;
  PetscCall(DMPlexSetPartitioner(*dm, part));
  PetscCall(DMPlexDistribute(*dm, 0, NULL, &dist));
  if (dist) {
    PetscCall(DMDestroy(dm));
    *dm = dist;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* METIS partition of the cells of a mesh that lies entirely on rank 0 into nparts parts, in the form of
   PetscPartitionerShellSetPartition(): sizes[nparts] cells per part and points[], the cells grouped by part
   (empty on the other ranks). The caller frees both with PetscFree2(). */
static PetscErrorCode MeshPartitionMetis(DM dm, PetscInt nparts, PetscInt **sizes, PetscInt **points)
{
  PetscInt nvtxs, *offsets = NULL, *adjacency = NULL, *part, *next;
  IS       numbering;

  PetscFunctionBeginUser;
  PetscCall(DMPlexCreatePartitionerGraph(dm, 0, &nvtxs, &offsets, &adjacency, &numbering)); /* cells sharing a face */
  PetscCall(PetscMalloc2(nparts, sizes, nvtxs, points));
  PetscCall(PetscMalloc2(nvtxs, &part, nparts, &next));
  if (nparts == 1 || nvtxs <= nparts) { /* METIS refuses one part; with as many parts as cells, one cell each */
    for (PetscInt v = 0; v < nvtxs; ++v) part[v] = nparts == 1 ? 0 : v;
  } else if (nvtxs > 0) {
    const PetscInt nedges = offsets[nvtxs];
    idx_t          n = (idx_t)nvtxs, ncon = 1, np = (idx_t)nparts, objval = 0, options[METIS_NOPTIONS], *xadj, *adjncy, *where;
    int            status;

    PetscCall(PetscMalloc3(nvtxs + 1, &xadj, nedges, &adjncy, nvtxs, &where));
    for (PetscInt v = 0; v <= nvtxs; ++v) xadj[v] = (idx_t)offsets[v];
    for (PetscInt e = 0; e < nedges; ++e) adjncy[e] = (idx_t)adjacency[e];
    METIS_SetDefaultOptions(options);
    options[METIS_OPTION_NUMBERING] = 0;
    options[METIS_OPTION_SEED]      = 0; /* the same partition on every run */
    /* recursive bisection for few parts, k-way for many, as the METIS manual advises */
    if (nparts <= 8)
      status = METIS_PartGraphRecursive(&n, &ncon, xadj, adjncy, NULL, NULL, NULL, &np, NULL, NULL, options, &objval, where);
    else
      status = METIS_PartGraphKway(&n, &ncon, xadj, adjncy, NULL, NULL, NULL, &np, NULL, NULL, options, &objval, where);
    PetscCheck(status == METIS_OK, PETSC_COMM_SELF, PETSC_ERR_LIB,
               "METIS partitioning of %" PetscInt_FMT " cells into %" PetscInt_FMT " parts failed (status %d)", nvtxs, nparts, status);
    PetscCall(PetscInfo(dm, "METIS: %" PetscInt_FMT " cells, %" PetscInt_FMT " parts, edge cut %d\n", nvtxs, nparts, (int)objval));
    for (PetscInt v = 0; v < nvtxs; ++v) part[v] = (PetscInt)where[v];
    PetscCall(PetscFree3(xadj, adjncy, where));
  }
  /* group the cells by part: counting sort (the graph vertices are the cells cStart.. in order on one rank) */
  for (PetscInt p = 0; p < nparts; ++p) (*sizes)[p] = 0;
  for (PetscInt v = 0; v < nvtxs; ++v) ++(*sizes)[part[v]];
  next[0] = 0;
  for (PetscInt p = 1; p < nparts; ++p) next[p] = next[p - 1] + (*sizes)[p - 1];
  for (PetscInt v = 0; v < nvtxs; ++v) (*points)[next[part[v]]++] = v;
  PetscCall(PetscFree2(part, next));
  PetscCall(PetscFree(offsets));
  PetscCall(PetscFree(adjacency));
  PetscCall(ISDestroy(&numbering));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Edge cut (faces shared by two ranks) and load imbalance (max over mean of the cells per rank) of a distributed
   mesh without overlap. A face lies on two ranks only if its two cells do; it is a leaf of the point SF on one. */
static PetscErrorCode MeshPartitionComputeStats(DM dm, MeshPartitionStats *stats)
{
  MPI_Comm        comm = PetscObjectComm((PetscObject)dm);
  PetscSF         sf;
  PetscInt        nleaves, dim, depth, cStart, cEnd, fStart, fEnd, ncells, cut = 0, cells_max, cells_total;
  const PetscInt *leaves;
  PetscMPIInt     size;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMPlexGetDepth(dm, &depth));
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  PetscCall(DMPlexGetHeightStratum(dm, 1, &fStart, &fEnd));
  PetscCall(DMGetPointSF(dm, &sf));
  PetscCall(PetscSFGetGraph(sf, NULL, &nleaves, &leaves, NULL));
  ncells = cEnd - cStart;
  for (PetscInt l = 0; l < nleaves; ++l) {
    const PetscInt p = leaves ? leaves[l] : l;

    ncells -= (p >= cStart && p < cEnd); /* a ghost cell (overlap): owned elsewhere */
    cut += (p >= fStart && p < fEnd);
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &cut, 1, MPIU_INT, MPI_SUM, comm));
  PetscCall(MPIU_Allreduce(&ncells, &cells_max, 1, MPIU_INT, MPI_MAX, comm));
  PetscCall(MPIU_Allreduce(&ncells, &cells_total, 1, MPIU_INT, MPI_SUM, comm));
  stats->edge_cut  = depth == dim ? cut : -1; /* an uninterpolated mesh has no faces to count */
  stats->imbalance = cells_total > 0 ? (PetscReal)cells_max * size / (PetscReal)cells_total : 1.0;
  stats->cells_max = cells_max;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Distributes the mesh *dm, which may lie entirely on rank 0, over the ranks of its communicator with the given
   partitioner (no overlap), replaces *dm by the distributed mesh and records the quality of the partition on it
   (MeshPartitionGetStats()). On one rank the mesh stays as it is. */
PetscErrorCode MeshPartitionDistribute(MeshPartitionerType type, DM *dm)
{
  MPI_Comm            comm = PetscObjectComm((PetscObject)*dm);
  PetscMPIInt         size, rank;
  PetscPartitioner    part;
  MeshPartitionStats *stats;
  PetscContainer      container;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  if (size > 1 && type != MESH_PARTITIONER_BOX) { /* box: built distributed (MeshCreateSimplexBox()) */
    PetscCall(PetscPartitionerCreate(comm, &part));
    switch (type) {
      case MESH_PARTITIONER_PTSCOTCH:
        PetscCall(PetscPartitionerSetType(part, PETSCPARTITIONERPTSCOTCH));
        break;
      case MESH_PARTITIONER_SIMPLE:
        PetscCall(PetscPartitionerSetType(part, PETSCPARTITIONERSIMPLE));
        break;
      case MESH_PARTITIONER_METIS: {
        PetscInt noff, *sizes, *points;

        PetscCall(MeshPartitionCellsOffRoot(*dm, &noff));
        if (noff > 0) { /* a mesh read in parallel: gather it on rank 0, where METIS runs */
          PetscPartitioner gather;

          PetscCall(PetscPartitionerCreate(comm, &gather));
          PetscCall(PetscPartitionerSetType(gather, PETSCPARTITIONERGATHER));
          PetscCall(MeshPartitionApply(gather, dm));
          PetscCall(PetscPartitionerDestroy(&gather));
        }
        PetscCall(MeshPartitionMetis(*dm, size, &sizes, &points));
        PetscCall(PetscPartitionerSetType(part, PETSCPARTITIONERSHELL));
        PetscCall(PetscPartitionerShellSetPartition(part, size, sizes, points));
        PetscCall(PetscFree2(sizes, points));
      } break;
      case MESH_PARTITIONER_BOX:
        break;
    }
    PetscCall(MeshPartitionApply(part, dm));
    PetscCall(PetscPartitionerDestroy(&part));
  }
  PetscCall(PetscNew(&stats));
  stats->partitioner = type;
  PetscCall(MeshPartitionComputeStats(*dm, stats));
  PetscCall(PetscContainerCreate(PETSC_COMM_SELF, &container));
  PetscCall(PetscContainerSetPointer(container, stats));
  PetscCall(PetscContainerSetUserDestroy(container, PetscContainerUserDestroyDefault));
  PetscCall(PetscObjectCompose((PetscObject)*dm, MESH_PARTITION_STATS_KEY, (PetscObject)container));
  PetscCall(PetscContainerDestroy(&container));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The edge cut and imbalance of dm as it is now (after refinements too), and the partitioner recorded by
   MeshPartitionDistribute() when dm is the mesh it distributed (otherwise stats->partitioner is left as it is). */
PetscErrorCode MeshPartitionGetStats(DM dm, MeshPartitionStats *stats)
{
  PetscContainer container;

  PetscFunctionBeginUser;
  PetscCall(PetscObjectQuery((PetscObject)dm, MESH_PARTITION_STATS_KEY, (PetscObject *)&container));
  if (container) {
    MeshPartitionStats *s;

    PetscCall(PetscContainerGetPointer(container, (void **)&s));
    stats->partitioner = s->partitioner;
  }
  PetscCall(MeshPartitionComputeStats(dm, stats));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The distribution's part of /run: the partitioner, the edge cut and the imbalance (MeshPartitionGetStats()). */
PetscErrorCode MeshPartitionWrite(const MeshPartitionStats *ps, PetscViewer v)
{
  PetscFunctionBeginUser;
  PetscCall(RunAttrString(v, MeshPartitionerTypes[ps->partitioner], "partitioner"));
  PetscCall(RunAttrInt(v, ps->edge_cut, "partition_edge_cut"));
  PetscCall(RunAttrReal(v, ps->imbalance, "partition_imbalance"));
  PetscFunctionReturn(PETSC_SUCCESS);
}

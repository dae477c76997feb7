/* The mesh of the HDF5 file, /geometry/vertices and /viz/topology/cells, as DMView() writes them with the format
   PETSC_VIEWER_HDF5_VIZ (PETSc 3.18's legacy coordinates and XDMF topology), without its two closures per cell.
   Meshes whose cells are not all of one type, or that are periodic, are left to DMView().
   One of PETSc 3.18's mirrors (docs/decisions.md, "PETSc 3.18's mirrors"). */
#include <petscsf.h>
#include <petscviewerhdf5.h>
#include "mesh.h"
#include "io.h"

/* The global number of each local vertex, the owners' numbering of /geometry/vertices: owned vertices in point order,
   rank after rank. */
static PetscErrorCode GlobalVertexNumbers(DM dm, PetscInt vStart, PetscInt vEnd, PetscInt **gnum)
{
  PetscSF     sf;
  PetscInt   *owned, nowned, offset = 0, pStart, pEnd, *all;
  PetscMPIInt rank;

  PetscFunctionBeginUser;
  PetscCall(MeshOwnedIndex(dm, vStart, vEnd, &owned, &nowned));
  PetscCallMPI(MPI_Exscan(&nowned, &offset, 1, MPIU_INT, MPI_SUM, PetscObjectComm((PetscObject)dm)));
  PetscCallMPI(MPI_Comm_rank(PetscObjectComm((PetscObject)dm), &rank));
  if (rank == 0) offset = 0; /* MPI leaves rank 0's result undefined */
  PetscCall(DMPlexGetChart(dm, &pStart, &pEnd));
  PetscCall(PetscMalloc1(pEnd - pStart, &all)); /* over the chart, as the point SF's roots and leaves are */
  for (PetscInt p = pStart; p < pEnd; ++p) all[p - pStart] = -1;
  for (PetscInt v = vStart; v < vEnd; ++v)
    if (owned[v - vStart] >= 0) all[v - pStart] = offset + owned[v - vStart];
  PetscCall(DMGetPointSF(dm, &sf));
  PetscCall(PetscSFBcastBegin(sf, MPIU_INT, all, all, MPI_REPLACE));
  PetscCall(PetscSFBcastEnd(sf, MPIU_INT, all, all, MPI_REPLACE));
  PetscCall(PetscMalloc1(vEnd - vStart, gnum));
  for (PetscInt v = vStart; v < vEnd; ++v) (*gnum)[v - vStart] = all[v - pStart];
  PetscCall(PetscFree(all));
  PetscCall(PetscFree(owned));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* /viz/topology/cells: the owned cells' vertices (global numbers) in closure order, turned as XDMF wants them; all
   cells of type ct with ncorners vertices. */
static PetscErrorCode ViewCells(DM dm, MeshClosure *mc, DMPolytopeType ct, PetscInt ncorners, PetscViewer viewer)
{
  PetscInt cStart, cEnd, *cell_owned, nowned, *gvert, *verts, dim = mc->dim, n = 0;
  IS       cells;

  PetscFunctionBeginUser;
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  PetscCall(MeshOwnedIndex(dm, cStart, cEnd, &cell_owned, &nowned));
  PetscCall(GlobalVertexNumbers(dm, mc->vstart, mc->vend, &gvert));
  PetscCall(PetscMalloc1(nowned * ncorners, &verts));
  for (PetscInt c = cStart; c < cEnd; ++c) {
    const PetscInt *cl;
    PetscInt        ncl, nv = 0, *cv = &verts[n];

    if (cell_owned[c - cStart] < 0) continue;
    PetscCall(MeshClosureGet(mc, c, PETSC_TRUE, &ncl, &cl));
    for (PetscInt k = 0; k < ncl; ++k)
      if (cl[2 * k] >= mc->vstart && cl[2 * k] < mc->vend) cv[nv++] = cl[2 * k];
    PetscCheck(nv == ncorners, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Cell %" PetscInt_FMT " has %" PetscInt_FMT " vertices, not %" PetscInt_FMT, c, nv,
               ncorners);
    PetscCall(DMPlexInvertCell(ct, cv)); /* DMPlexReorderCell() */
    for (PetscInt k = 0; k < nv; ++k) cv[k] = gvert[cv[k] - mc->vstart];
    n += nv;
  }
  PetscCall(ISCreateGeneral(PetscObjectComm((PetscObject)dm), n, verts, PETSC_OWN_POINTER, &cells));
  PetscCall(ISSetBlockSize(cells, ncorners));
  PetscCall(PetscObjectSetName((PetscObject)cells, "cells"));
  PetscCall(PetscViewerHDF5PushGroup(viewer, "/viz"));
  PetscCall(PetscViewerHDF5WriteGroup(viewer, NULL));
  PetscCall(PetscViewerHDF5PopGroup(viewer));
  PetscCall(PetscViewerHDF5PushGroup(viewer, "/viz/topology"));
  PetscCall(ISView(cells, viewer));
  PetscCall(PetscViewerHDF5WriteObjectAttribute(viewer, (PetscObject)cells, "cell_corners", PETSC_INT, &ncorners));
  PetscCall(PetscViewerHDF5WriteObjectAttribute(viewer, (PetscObject)cells, "cell_dim", PETSC_INT, &dim));
  PetscCall(PetscViewerHDF5PopGroup(viewer));
  PetscCall(ISDestroy(&cells));
  PetscCall(PetscFree(gvert));
  PetscCall(PetscFree(cell_owned));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* /geometry/vertices: the coordinates of the owned vertices in point order, rank after rank (the global coordinate
   vector, which DMGetCoordinates() would build by a scatter), scaled to PETSc's unit of length. */
static PetscErrorCode ViewVertices(DM dm, const MeshClosure *mc, PetscViewer viewer)
{
  Vec                coords, copy;
  PetscSection       csec;
  PetscReal          scale;
  PetscInt          *owned, nowned, cdim;
  const PetscScalar *xc;
  PetscScalar       *y;

  PetscFunctionBeginUser;
  PetscCall(DMPlexGetScale(dm, PETSC_UNIT_LENGTH, &scale));
  PetscCall(DMGetCoordinateDim(dm, &cdim));
  PetscCall(DMGetCoordinateSection(dm, &csec));
  PetscCall(DMGetCoordinatesLocal(dm, &coords));
  PetscCall(MeshOwnedIndex(dm, mc->vstart, mc->vend, &owned, &nowned));
  PetscCall(VecCreate(PetscObjectComm((PetscObject)dm), &copy)); /* no DM: a plain dataset, not DMPlex's field layout */
  PetscCall(VecSetSizes(copy, nowned * cdim, PETSC_DETERMINE));
  PetscCall(VecSetBlockSize(copy, cdim));
  PetscCall(VecSetType(copy, VECSTANDARD));
  PetscCall(VecGetArrayRead(coords, &xc));
  PetscCall(VecGetArray(copy, &y));
  for (PetscInt v = mc->vstart; v < mc->vend; ++v) {
    PetscInt off;

    if (owned[v - mc->vstart] < 0) continue;
    PetscCall(PetscSectionGetOffset(csec, v, &off));
    for (PetscInt d = 0; d < cdim; ++d) y[owned[v - mc->vstart] * cdim + d] = scale * xc[off + d];
  }
  PetscCall(VecRestoreArray(copy, &y));
  PetscCall(VecRestoreArrayRead(coords, &xc));
  PetscCall(PetscFree(owned));
  PetscCall(PetscObjectSetName((PetscObject)copy, "vertices"));
  PetscCall(PetscViewerHDF5PushGroup(viewer, "/geometry"));
  PetscCall(PetscViewerPushFormat(viewer, PETSC_VIEWER_NATIVE));
  PetscCall(VecView(copy, viewer));
  PetscCall(PetscViewerPopFormat(viewer));
  PetscCall(PetscViewerHDF5PopGroup(viewer));
  PetscCall(VecDestroy(&copy));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The mesh, with the format PETSC_VIEWER_HDF5_VIZ pushed on viewer. */
PetscErrorCode OutputViewMesh(DM dm, PetscViewer viewer)
{
  MeshClosure mc;
  PetscInt    height, cStart, cEnd, v[3];
  PetscBool   localized;
  DMLabel     cut;

  PetscFunctionBeginUser;
  PetscCall(MeshClosureCreate(dm, &mc));
  PetscCall(DMGetCoordinatesLocalized(dm, &localized));
  PetscCall(DMGetLabel(dm, "periodic_cut", &cut));
  PetscCall(DMPlexGetVTKCellHeight(dm, &height));
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  /* one cell type on all ranks (ranks without cells aside): the largest type and the largest of minus the type */
  v[0] = cEnd > cStart ? (PetscInt)mc.type[mc.depth] : PETSC_MIN_INT;
  v[1] = cEnd > cStart ? -(PetscInt)mc.type[mc.depth] : PETSC_MIN_INT;
  v[2] = (mc.by_depth || cEnd == cStart) && !localized && !cut && height == 0 ? 0 : 1;
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, v, 3, MPIU_INT, MPI_MAX, PetscObjectComm((PetscObject)dm)));
  if (!v[2] && v[0] >= 0 && v[0] == -v[1]) {
    const DMPolytopeType ct = (DMPolytopeType)v[0];

    PetscCall(ViewVertices(dm, &mc, viewer));
    PetscCall(ViewCells(dm, &mc, ct, DMPolytopeTypeGetNumVertices(ct), viewer));
  } else
    PetscCall(DMView(dm, viewer));
  PetscCall(MeshClosureDestroy(&mc));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* HDF5 writer: mesh and vertex fields in PETSc's layout (petsc_gen_xdmf.py reads it), run metadata
   as attributes of /run, an .xdmf beside it. Written under temporary names and renamed when complete (output_file.c). */
#define _DEFAULT_SOURCE /* POSIX and BSD calls (mkstemp, lstat, sigaction, flock) under -std=c99 */
#include <errno.h>
#include <string.h>
#include <sys/statvfs.h>
#include <petscsf.h>
#include <petscviewerhdf5.h>
#include "app.h"
#include "contact.h"
#include "mesh.h"
#include "io.h"

PetscErrorCode OutputGetOptions(MPI_Comm comm, RunOptions *opt)
{
  PetscBool set;

  PetscFunctionBeginUser;
  PetscOptionsBegin(comm, NULL, "Output", "Signorini");
  PetscCall(PetscSNPrintf(opt->output, sizeof(opt->output), "output/%s.h5", opt->scene_name));
  PetscCall(PetscOptionsString("-output", "HDF5 output file (default output/<scene>.h5)", NULL, opt->output, opt->output, sizeof(opt->output), &set));
  opt->output_dmview = PETSC_FALSE;
  PetscCall(PetscOptionsBool("-output_dmview", "Write the mesh with PETSc's DMView() (the same datasets, slower)", "OutputViewMesh",
                             opt->output_dmview, &opt->output_dmview, NULL));
  PetscOptionsEnd();
  PetscCall(OutputFileCheckTarget(comm, opt->output, (PetscBool)!set)); /* the default directory is created; a user's must exist */
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Writes /vertex_fields/<name of v> as an (n_vertices, nc) dataset in the vertex order of /geometry/vertices. */
static PetscErrorCode ViewVertexField(Vec v, PetscInt nc, PetscViewer viewer)
{
  Vec                plain;
  PetscInt           n;
  const PetscScalar *a;
  const char        *name;

  PetscFunctionBeginUser;
  PetscCall(VecGetLocalSize(v, &n));
  PetscCall(VecGetArrayRead(v, &a));
  PetscCall(VecCreateMPIWithArray(PetscObjectComm((PetscObject)v), nc, n, PETSC_DECIDE, a, &plain));
  PetscCall(PetscObjectGetName((PetscObject)v, &name));
  PetscCall(PetscObjectSetName((PetscObject)plain, name));
  PetscCall(PetscViewerHDF5PushGroup(viewer, "/vertex_fields"));
  PetscCall(VecView(plain, viewer));
  PetscCall(PetscViewerHDF5WriteObjectAttribute(viewer, (PetscObject)plain, "vector_field_type", PETSC_STRING, nc > 1 ? "vector" : "scalar"));
  PetscCall(PetscViewerHDF5PopGroup(viewer));
  PetscCall(VecDestroy(&plain));
  PetscCall(VecRestoreArrayRead(v, &a));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The state of a solution at the owned vertices (plain vectors, in the order of /geometry/vertices), the fields a load
   path keeps at every step: the displacement (with the Dirichlet values), the nodal contact pressure, the normal gap
   g - u_n and the Gamma_C indicator, from u and the contact set as PostprocessContact() left it. */
PetscErrorCode OutputStateFields(DM dm, Contact contact, Vec loc_bc, Vec u, Vec fields[OUTPUT_STATE_FIELDS])
{
  const char *const  names[OUTPUT_STATE_FIELDS] = {"displacement", "contact_pressure", "normal_gap", "contact_boundary", "contact_reaction"};
  const ContactSet  *cs;
  MPI_Comm           comm = PetscObjectComm((PetscObject)dm);
  Vec                locU;
  PetscSection       usec;
  PetscInt           dim, vStart, vEnd, nowned = 0, *index = NULL;
  const PetscScalar *lu, *x;
  PetscScalar       *d, *p, *g, *m, *fr;

  PetscFunctionBeginUser;
  PetscCall(ContactGetSet(contact, &cs));
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  PetscCall(MeshOwnedIndex(dm, vStart, vEnd, &index, &nowned)); /* plain vectors over the owned vertices, no DM clone */
  PetscCall(DMGetLocalSection(dm, &usec));
  PetscCall(VecCreateMPI(comm, nowned * dim, PETSC_DETERMINE, &fields[0]));
  PetscCall(VecCreateMPI(comm, nowned, PETSC_DETERMINE, &fields[1]));
  PetscCall(VecDuplicate(fields[1], &fields[2]));
  PetscCall(VecDuplicate(fields[1], &fields[3]));
  PetscCall(VecDuplicate(fields[1], &fields[4]));
  for (PetscInt f = 0; f < OUTPUT_STATE_FIELDS; ++f) {
    PetscCall(PetscObjectSetName((PetscObject)fields[f], names[f]));
    PetscCall(VecZeroEntries(fields[f]));
  }
  PetscCall(DMGetLocalVector(dm, &locU));
  PetscCall(VecCopy(loc_bc, locU)); /* the Dirichlet values, inserted once by ProblemSetUp() */
  PetscCall(DMGlobalToLocal(dm, u, INSERT_VALUES, locU));
  PetscCall(VecGetArrayRead(locU, &lu));
  PetscCall(VecGetArray(fields[0], &d));
  for (PetscInt v = vStart; v < vEnd; ++v) {
    PetscInt uoff;

    if (index[v - vStart] < 0) continue; /* not owned */
    PetscCall(PetscSectionGetOffset(usec, v, &uoff));
    for (PetscInt c = 0; c < dim; ++c) d[index[v - vStart] * dim + c] = lu[uoff + c];
  }
  PetscCall(VecRestoreArray(fields[0], &d));
  PetscCall(VecRestoreArrayRead(locU, &lu));
  PetscCall(DMRestoreLocalVector(dm, &locU));
  PetscCall(VecGetArrayRead(u, &x));
  PetscCall(VecGetArray(fields[1], &p));
  PetscCall(VecGetArray(fields[2], &g));
  PetscCall(VecGetArray(fields[3], &m));
  PetscCall(VecGetArray(fields[4], &fr));
  for (PetscInt i = 0; i < cs->n; ++i) {
    PetscInt goff;

    if (!cs->is_vertex[i]) continue;
    goff = index[cs->point[i] - vStart];
    if (goff < 0) continue; /* owned by another rank */
    p[goff]  = cs->pressure[i];
    g[goff]  = -ContactNodePenetration(cs, dim, i, x);
    m[goff]  = 1.0;
    fr[goff] = cs->reaction[i]; /* the nodal force of the obstacle along n */
  }
  PetscCall(VecRestoreArray(fields[4], &fr));
  PetscCall(VecRestoreArray(fields[3], &m));
  PetscCall(VecRestoreArray(fields[2], &g));
  PetscCall(VecRestoreArray(fields[1], &p));
  PetscCall(VecRestoreArrayRead(u, &x));
  PetscCall(PetscFree(index));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The vertex fields: the state (OutputStateFields(): displacement, contact pressure, normal gap g - u_n, Gamma_C
   indicator), of the last solution or, with a load path, of every step as a time series (the step the first dimension,
   PETSc's timestepping); the nodal reaction and lumped area; the exact solution and error when the scene has one; the
   pressure's band with -bars. */
static PetscErrorCode WriteVertexFields(DM dm, const OutputContent *out, Vec u, PetscViewer viewer)
{
  const ContactSet  *cs;
  DM                 cdm;
  Vec                state[OUTPUT_STATE_FIELDS], area, exact = NULL, error = NULL, coords;
  PetscSection       csec;
  PetscInt           dim, vStart, vEnd, nowned = 0, *index = NULL;
  const PetscScalar *xc, *d;
  PetscScalar       *ar, *ex = NULL, *er = NULL;

  PetscFunctionBeginUser;
  PetscCall(ContactGetSet(out->contact, &cs));
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  PetscCall(MeshOwnedIndex(dm, vStart, vEnd, &index, &nowned));
  PetscCall(OutputStateFields(dm, out->contact, out->loc_bc, u, state));
  if (out->nsteps) {
    for (PetscInt f = 0; f < OUTPUT_STATE_FIELDS; ++f) {
      PetscCall(PetscViewerHDF5PushTimestepping(viewer));
      for (PetscInt k = 0; k < out->nsteps; ++k) {
        PetscCall(PetscViewerHDF5SetTimestep(viewer, k));
        PetscCall(ViewVertexField(out->step_fields[k * OUTPUT_STATE_FIELDS + f], f ? 1 : dim, viewer));
      }
      PetscCall(PetscViewerHDF5PopTimestepping(viewer));
    }
  } else
    for (PetscInt f = 0; f < OUTPUT_STATE_FIELDS; ++f) PetscCall(ViewVertexField(state[f], f ? 1 : dim, viewer));
  PetscCall(VecDuplicate(state[1], &area));
  PetscCall(PetscObjectSetName((PetscObject)area, "contact_area")); /* the lumped boundary mass: reaction / area is a pressure */
  PetscCall(VecZeroEntries(area));
  PetscCall(VecGetArray(area, &ar));
  for (PetscInt i = 0; i < cs->n; ++i) {
    const PetscInt goff = cs->is_vertex[i] ? index[cs->point[i] - vStart] : -1;

    if (goff >= 0) ar[goff] = cs->weight[i]; /* skips non-vertices and vertices owned by another rank */
  }
  PetscCall(VecRestoreArray(area, &ar));
  PetscCall(ViewVertexField(area, 1, viewer));
  if (out->scene->exact) {
    PetscCall(DMGetCoordinateDM(dm, &cdm));
    PetscCall(DMGetLocalSection(cdm, &csec));
    PetscCall(DMGetCoordinatesLocal(dm, &coords));
    PetscCall(VecDuplicate(state[0], &exact));
    PetscCall(VecDuplicate(state[0], &error));
    PetscCall(PetscObjectSetName((PetscObject)exact, "exact_displacement"));
    PetscCall(PetscObjectSetName((PetscObject)error, "error"));
    PetscCall(VecGetArray(exact, &ex));
    PetscCall(VecGetArray(error, &er));
    PetscCall(VecGetArrayRead(state[0], &d));
    PetscCall(VecGetArrayRead(coords, &xc));
    for (PetscInt v = vStart; v < vEnd; ++v) {
      PetscInt  goff, coff;
      PetscReal xv[3];

      if (index[v - vStart] < 0) continue; /* not owned */
      goff = index[v - vStart] * dim;
      PetscCall(PetscSectionGetOffset(csec, v, &coff));
      for (PetscInt c = 0; c < dim; ++c) xv[c] = PetscRealPart(xc[coff + c]);
      PetscCall((*out->scene->exact)(dim, 0.0, xv, dim, &ex[goff], (void *)out->scene->constants));
      for (PetscInt c = 0; c < dim; ++c) er[goff + c] = d[goff + c] - ex[goff + c];
    }
    PetscCall(VecRestoreArrayRead(coords, &xc));
    PetscCall(VecRestoreArrayRead(state[0], &d));
    PetscCall(VecRestoreArray(exact, &ex));
    PetscCall(VecRestoreArray(error, &er));
    PetscCall(ViewVertexField(exact, dim, viewer));
    PetscCall(ViewVertexField(error, dim, viewer));
  }
  if (out->bars->pressure_band) { /* -bars: the band of the nodal pressure (src/estimate/bars.c), 0 off Gamma_C */
    Vec          band;
    PetscScalar *bv;

    PetscCall(VecDuplicate(state[1], &band));
    PetscCall(PetscObjectSetName((PetscObject)band, "contact_pressure_bar"));
    PetscCall(VecZeroEntries(band));
    PetscCall(VecGetArray(band, &bv));
    for (PetscInt i = 0; i < out->bars->npressure; ++i) {
      const PetscInt goff = cs->is_vertex[i] ? index[cs->point[i] - vStart] : -1;

      if (goff >= 0) bv[goff] = out->bars->pressure_bar[i];
    }
    PetscCall(VecRestoreArray(band, &bv));
    PetscCall(ViewVertexField(band, 1, viewer));
    PetscCall(VecDestroy(&band));
  }
  PetscCall(VecDestroy(&exact));
  PetscCall(VecDestroy(&error));
  for (PetscInt f = 0; f < OUTPUT_STATE_FIELDS; ++f) PetscCall(VecDestroy(&state[f]));
  PetscCall(VecDestroy(&area));
  PetscCall(PetscFree(index));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* /cell_fields/<name>: a value of each owned cell (values[] over the local cells), in the cell order of /viz/topology/cells. */
static PetscErrorCode ViewCellField(DM dm, const char name[], const PetscReal values[], PetscViewer viewer)
{
  PetscInt     cStart, cEnd, *index, nowned;
  Vec          v;
  PetscScalar *a;

  PetscFunctionBeginUser;
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  PetscCall(MeshOwnedIndex(dm, cStart, cEnd, &index, &nowned));
  PetscCall(VecCreateMPI(PetscObjectComm((PetscObject)dm), nowned, PETSC_DETERMINE, &v));
  PetscCall(PetscObjectSetName((PetscObject)v, name));
  PetscCall(VecGetArray(v, &a));
  for (PetscInt c = cStart; c < cEnd; ++c)
    if (index[c - cStart] >= 0) a[index[c - cStart]] = values[c - cStart];
  PetscCall(VecRestoreArray(v, &a));
  PetscCall(PetscViewerHDF5PushGroup(viewer, "/cell_fields"));
  PetscCall(VecView(v, viewer));
  PetscCall(PetscViewerHDF5WriteObjectAttribute(viewer, (PetscObject)v, "vector_field_type", PETSC_STRING, "scalar"));
  PetscCall(PetscViewerHDF5PopGroup(viewer));
  PetscCall(VecDestroy(&v));
  PetscCall(PetscFree(index));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The estimate's cell fields: error_indicator (eta_T) and error_density (eta_T / |T|^1/2). */
static PetscErrorCode WriteCellFields(DM dm, const OutputContent *out, PetscViewer viewer)
{
  const ErrorEstimate *est = out->estimate;
  PetscInt             cStart, cEnd;

  PetscFunctionBeginUser;
  if (!est->computed) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  PetscCheck(est->ncells == cEnd - cStart, PETSC_COMM_SELF, PETSC_ERR_PLIB, "The estimate's cells are not the mesh's");
  PetscCall(ViewCellField(dm, "error_indicator", est->cell, viewer));
  PetscCall(ViewCellField(dm, "error_density", est->density, viewer));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The group /run with the mesh's size: the dimension, the displacement's degree, the ranks, the owned cells, vertices
   and unknowns; the run's results follow, each written by its module (OutputResultsWriter). */
static PetscErrorCode WriteMeshSize(DM dm, PetscInt degree, Vec u, PetscViewer v, PetscInt ncells, PetscInt nverts)
{
  PetscMPIInt size;
  PetscInt    dim, ndofs;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(PetscObjectComm((PetscObject)dm), &size));
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(VecGetSize(u, &ndofs));
  PetscCall(PetscViewerHDF5WriteGroup(v, "/run"));
  PetscCall(RunAttrInt(v, dim, "dim"));
  PetscCall(RunAttrInt(v, degree, "degree"));
  PetscCall(RunAttrInt(v, size, "nprocs"));
  PetscCall(RunAttrInt(v, ncells, "n_cells"));
  PetscCall(RunAttrInt(v, nverts, "n_vertices"));
  PetscCall(RunAttrInt(v, ndofs, "n_dofs"));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* One node or cell attribute of an XDMF grid: the whole dataset /group/name (n values of nc components), or with
   step >= 0 the step's slab of a load path's time series (nsteps x n [x nc], the step the first dimension). */
static void XdmfAttribute(FILE *fp, const char h5name[], const char group[], const char name[], const char center[], PetscInt n, PetscInt nc,
                          PetscInt step, PetscInt nsteps)
{
  char dims[64];

  if (nc > 1)
    snprintf(dims, sizeof(dims), "%d %d", (int)n, (int)nc);
  else
    snprintf(dims, sizeof(dims), "%d", (int)n);
  fprintf(fp, "   <Attribute Name=\"%s\" AttributeType=\"%s\" Center=\"%s\">\n", name, nc > 1 ? "Vector" : "Scalar", center);
  if (step < 0)
    fprintf(fp, "    <DataItem Dimensions=\"%s\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">%s:/%s/%s</DataItem>\n", dims, h5name, group,
            name);
  else {
    fprintf(fp, "    <DataItem ItemType=\"HyperSlab\" Dimensions=\"%s\" Type=\"HyperSlab\">\n", dims);
    if (nc > 1)
      fprintf(fp, "     <DataItem Dimensions=\"3 3\" Format=\"XML\">%d 0 0 1 1 1 1 %d %d</DataItem>\n", (int)step, (int)n, (int)nc);
    else
      fprintf(fp, "     <DataItem Dimensions=\"3 2\" Format=\"XML\">%d 0 1 1 1 %d</DataItem>\n", (int)step, (int)n);
    fprintf(fp, "     <DataItem Dimensions=\"%d %s\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">%s:/%s/%s</DataItem>\n", (int)nsteps, dims,
            h5name, group, name);
    fprintf(fp, "    </DataItem>\n");
  }
  fprintf(fp, "   </Attribute>\n");
}

/* XDMF for ParaView into the file xdmf, pointing into h5name, the final .h5 beside it (rank 0 only). The reals are
   declared 8-byte (XDMF's default precision is 4: ParaView would read them as floats). With a load path, a temporal
   collection of one grid per step (time = the step's number, 1, 2, ...: a path may go back to a factor, which a time
   cannot), each with the step's state fields; the fields of the last solution only (reaction, area, exact solution,
   band, estimate) are in the last step's grid. */
static PetscErrorCode WriteXdmf(const OutputContent *out, const char xdmf[], const char h5name[], PetscInt dim, PetscInt ncells, PetscInt ncorners,
                                PetscInt nverts)
{
  const char    *fields[] = {"displacement",     "contact_pressure", "normal_gap",         "contact_boundary",
                             "contact_reaction", "contact_area",     "exact_displacement", "error"};
  const PetscInt ncomp[]  = {dim, 1, 1, 1, 1, 1, dim, dim};
  const PetscInt nfields = out->scene->exact ? 8 : 6, nsteps = out->nsteps;
  const char    *topo = dim == 2 ? (ncorners == 3 ? "Triangle" : "Quadrilateral") : (ncorners == 4 ? "Tetrahedron" : "Hexahedron");
  FILE          *fp;
  int            bad;

  PetscFunctionBeginUser;
  fp = fopen(xdmf, "w");
  PetscCheck(fp, PETSC_COMM_SELF, PETSC_ERR_FILE_OPEN, "%s", strerror(errno));
  fprintf(fp, "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"2.0\">\n <Domain>\n");
  if (nsteps) fprintf(fp, "  <Grid Name=\"load path\" GridType=\"Collection\" CollectionType=\"Temporal\">\n");
  for (PetscInt k = nsteps ? 0 : -1; k < nsteps; ++k) {
    const PetscBool last = (PetscBool)(k == nsteps - 1);

    if (k < 0)
      fprintf(fp, "  <Grid Name=\"mesh\" GridType=\"Uniform\">\n");
    else
      fprintf(fp, "  <Grid Name=\"step %d\" GridType=\"Uniform\">\n   <Time Value=\"%d\"/>\n", (int)(k + 1), (int)(k + 1));
    fprintf(fp, "   <Topology TopologyType=\"%s\" NumberOfElements=\"%d\">\n", topo, (int)ncells);
    fprintf(fp, "    <DataItem Dimensions=\"%d %d\" NumberType=\"Int\" Format=\"HDF\">%s:/viz/topology/cells</DataItem>\n   </Topology>\n",
            (int)ncells, (int)ncorners, h5name);
    fprintf(fp, "   <Geometry GeometryType=\"%s\">\n", dim == 2 ? "XY" : "XYZ");
    fprintf(
        fp,
        "    <DataItem Dimensions=\"%d %d\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">%s:/geometry/vertices</DataItem>\n   </Geometry>\n",
        (int)nverts, (int)dim, h5name);
    for (PetscInt f = 0; f < nfields; ++f) {
      if (f >= OUTPUT_STATE_FIELDS && !last) continue; /* the last solution's only */
      XdmfAttribute(fp, h5name, "vertex_fields", fields[f], "Node", nverts, ncomp[f], f < OUTPUT_STATE_FIELDS ? k : -1, nsteps);
    }
    if (out->bars->pressure_band && last) XdmfAttribute(fp, h5name, "vertex_fields", "contact_pressure_bar", "Node", nverts, 1, -1, 0);
    for (PetscInt f = 0; f < 2 && out->estimate->computed && last; ++f)
      XdmfAttribute(fp, h5name, "cell_fields", f ? "error_density" : "error_indicator", "Cell", ncells, 1, -1, 0);
    fprintf(fp, "  </Grid>\n");
  }
  if (nsteps) fprintf(fp, "  </Grid>\n");
  fprintf(fp, " </Domain>\n</Xdmf>\n");
  bad = fflush(fp) != 0 || ferror(fp);
  bad = (fclose(fp) != 0) || bad;
  PetscCheck(!bad, PETSC_COMM_SELF, PETSC_ERR_FILE_WRITE, "%s", strerror(errno));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The HDF5 file, written into the temporary h5tmp, and the XDMF file into xdmftmp, both in the current directory. */
static PetscErrorCode WriteFiles(DM dm, const OutputContent *out, Vec u, const char h5tmp[], const char xdmftmp[], const char h5name[])
{
  MPI_Comm    comm = PetscObjectComm((PetscObject)dm);
  PetscViewer viewer;
  PetscInt    dim, cStart, cEnd, vStart, vEnd, ncells, nverts, ncorners = 0;
  PetscMPIInt rank;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  PetscCall(MeshCountOwned(dm, cStart, cEnd, &ncells));
  PetscCall(MeshCountOwned(dm, vStart, vEnd, &nverts));
  if (cEnd > cStart) PetscCall(DMPlexGetConeSize(dm, cStart, &ncorners));
  if (dim == 3 && ncorners == 6) ncorners = 8; /* a hex has 6 faces and 8 corners; a triangle, quad or tet as many corners as faces */
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &ncorners, 1, MPIU_INT, MPI_MAX, comm));

  PetscCall(PetscViewerHDF5Open(comm, h5tmp, FILE_MODE_WRITE, &viewer));
  PetscCall(PetscViewerPushFormat(viewer, PETSC_VIEWER_HDF5_VIZ));
  if (out->dmview)
    PetscCall(DMView(dm, viewer));
  else
    PetscCall(OutputViewMesh(dm, viewer)); /* DMView() without its closures per cell */
  PetscCall(WriteVertexFields(dm, out, u, viewer));
  PetscCall(WriteCellFields(dm, out, viewer));
  PetscCall(PetscViewerPopFormat(viewer));
  PetscCall(WriteMeshSize(dm, out->degree, u, viewer, ncells, nverts));
  PetscCall(out->write_results(dm, u, viewer, out->ctx)); /* each module's own results (src/main.c) */
  PetscCall(PetscViewerDestroy(&viewer));
  if (rank == 0) PetscCall(WriteXdmf(out, xdmftmp, h5name, dim, ncells, ncorners, nverts));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Writes FILE.h5 and FILE.xdmf (output_file.c: temporaries renamed when complete), from inside their directory
   (OutputFileEnterDirectory()). An I/O error is reported in one sentence naming the file and the cause. */
PetscErrorCode OutputWriteHDF5(DM dm, Vec u, const OutputContent *out)
{
  MPI_Comm       comm = PetscObjectComm((PetscObject)dm);
  char           dir[PETSC_MAX_PATH_LEN], base[PETSC_MAX_PATH_LEN], xdmf[PETSC_MAX_PATH_LEN], temps[2][PETSC_MAX_PATH_LEN];
  char           tdir[PETSC_MAX_PATH_LEN], h5tmp[PETSC_MAX_PATH_LEN], xdmftmp[PETSC_MAX_PATH_LEN];
  const char    *targets[2] = {xdmf, out->path};
  PetscErrorCode ierr;
  int            cwd, err = 0, local_failed, failed;
  H5E_auto2_t    h5_func;
  void          *h5_data;

  PetscFunctionBeginUser;
  PetscCall(OutputFileSplitPath(out->path, dir, sizeof(dir), base, sizeof(base)));
  PetscCall(OutputFileXdmfName(out->path, xdmf, sizeof(xdmf)));
  PetscCall(OutputFileCreateTemps(comm, dir, 2, temps));                                  /* [0] the XDMF file, [1] the HDF5 file */
  PetscCall(OutputFileSplitPath(temps[0], tdir, sizeof(tdir), xdmftmp, sizeof(xdmftmp))); /* names inside dir */
  PetscCall(OutputFileSplitPath(temps[1], tdir, sizeof(tdir), h5tmp, sizeof(h5tmp)));
  PetscCall(OutputFileEnterDirectory(temps[1], &cwd, h5tmp, sizeof(h5tmp)));
  (void)H5Eget_auto2(H5E_DEFAULT, &h5_func, &h5_data);
  (void)H5Eset_auto2(H5E_DEFAULT, NULL, NULL); /* HDF5's own error stack: replaced by the sentence below */
  PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
  errno = 0;
  ierr  = WriteFiles(dm, out, u, h5tmp, xdmftmp, base);
  err   = errno;
  PetscCall(PetscPopErrorHandler());
  (void)H5Eset_auto2(H5E_DEFAULT, h5_func, h5_data);
  PetscCall(OutputFileLeaveDirectory(cwd));
  local_failed = ierr != 0;
  PetscCallMPI(MPI_Allreduce(&local_failed, &failed, 1, MPI_INT, MPI_MAX, comm));
  if (failed) {
    const char    *text     = NULL;
    char          *specific = NULL, cause[256] = "the write failed on another rank";
    struct statvfs fs;

    PetscCall(OutputFileDiscardTemps(comm));
    if (ierr) PetscCall(PetscErrorMessage(ierr, &text, &specific));
    if (statvfs(dir, &fs) == 0 && fs.f_bavail == 0)
      PetscCall(PetscSNPrintf(cause, sizeof(cause), "no space left on the device of '%s'", dir));
    else if (err == ENOSPC || err == EDQUOT || err == EFBIG || err == EIO || err == EROFS || err == EACCES)
      PetscCall(PetscSNPrintf(cause, sizeof(cause), "%s", strerror(err)));
    else if (ierr)
      PetscCall(PetscSNPrintf(cause, sizeof(cause), "%s", specific && specific[0] ? specific : text));
    SETERRQ(PETSC_COMM_SELF, PETSC_ERR_FILE_WRITE, "Cannot write the output file %s: %s", out->path, cause);
  }
  PetscCall(OutputFileCommit(comm, dir, 2, temps, targets));
  PetscFunctionReturn(PETSC_SUCCESS);
}

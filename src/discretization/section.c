/* The local section of P1/Q1 displacements (dim unknowns at each vertex, the Dirichlet components constrained), built
   as DMCreateLocalSection() builds it, in the same order of calls, but without its cell-type lookup for every mesh
   point: PETSc 3.18 makes that label's strata hash sets just before (DMPlexGetGhostCellStratum()), so each lookup is a
   hash-set query. Other discretizations (higher degrees, several fields, anchors) are left to PETSc. -section_check
   builds both and compares them (PetscSectionCompare()).
   One of PETSc 3.18's mirrors (docs/decisions.md, "PETSc 3.18's mirrors"). */
#include "discretization.h"
#include "physics.h"

/* The points of the essential condition bd (its label's strata, cells left out) and its components (NULL: all). */
static PetscErrorCode SectionBoundaryPoints(DM dm, PetscDS ds, PetscInt bd, PetscBool *essential, IS *points, IS *comps)
{
  DMLabel                 label;
  const PetscInt         *values, *bcomps;
  PetscInt                nvalues, ncomps, field, cStart, cEnd, n = 0, *idx;
  DMBoundaryConditionType type;

  PetscFunctionBeginUser;
  *points = *comps = NULL;
  PetscCall(PetscDSGetBoundary(ds, bd, NULL, &type, NULL, &label, &nvalues, &values, &field, &ncomps, &bcomps, NULL, NULL, NULL));
  *essential = (PetscBool)(label && (type & DM_BC_ESSENTIAL));
  if (!*essential) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  if (ncomps) PetscCall(ISCreateGeneral(PETSC_COMM_SELF, ncomps, bcomps, PETSC_COPY_VALUES, comps));
  for (PetscInt pass = 0; pass < 2; ++pass) {
    if (pass) PetscCall(PetscMalloc1(n, &idx));
    n = 0;
    for (PetscInt v = 0; v < nvalues; ++v) {
      IS              is;
      const PetscInt *p;
      PetscInt        np;

      PetscCall(DMLabelGetStratumIS(label, values[v], &is));
      if (!is) continue;
      PetscCall(ISGetLocalSize(is, &np));
      PetscCall(ISGetIndices(is, &p));
      for (PetscInt i = 0; i < np; ++i)
        if (p[i] < cStart || p[i] >= cEnd) {
          if (pass) idx[n] = p[i];
          ++n;
        }
      PetscCall(ISRestoreIndices(is, &p));
      PetscCall(ISDestroy(&is));
    }
  }
  PetscCall(ISCreateGeneral(PETSC_COMM_SELF, n, idx, PETSC_OWN_POINTER, points));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* DMPlexCreateSection() for one field of nc components with ndof unknowns per vertex and the conditions nbc, points[],
   comps[]: dofs, constraint counts, set-up, then the constraint indices field by field and of the points. */
static PetscErrorCode SectionBuild(DM dm, PetscInt nc, PetscInt ndof, PetscInt nbc, IS points[], IS comps[], PetscSection *section)
{
  PetscInt pStart, pEnd, vStart, vEnd, max_cdof = 0, *indices;

  PetscFunctionBeginUser;
  PetscCall(PetscSectionCreate(PetscObjectComm((PetscObject)dm), section));
  PetscCall(PetscSectionSetNumFields(*section, 1));
  PetscCall(PetscSectionSetFieldComponents(*section, 0, nc));
  PetscCall(DMPlexGetChart(dm, &pStart, &pEnd));
  PetscCall(PetscSectionSetChart(*section, pStart, pEnd));
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  for (PetscInt v = vStart; v < vEnd; ++v) { /* the other points have none */
    PetscCall(PetscSectionSetFieldDof(*section, v, 0, ndof));
    PetscCall(PetscSectionAddDof(*section, v, ndof));
  }
  for (PetscInt bc = 0; bc < nbc; ++bc) { /* constraint counts: DMPlexCreateSectionBCDof() */
    const PetscInt *idx;
    PetscInt        n, cnc = -1;

    if (comps[bc]) PetscCall(ISGetLocalSize(comps[bc], &cnc));
    PetscCall(ISGetLocalSize(points[bc], &n));
    PetscCall(ISGetIndices(points[bc], &idx));
    for (PetscInt i = 0; i < n; ++i) {
      PetscInt nconst;

      PetscCall(PetscSectionGetFieldDof(*section, idx[i], 0, &nconst));
      if (cnc > 0) nconst = (nconst / nc) * cnc;
      PetscCall(PetscSectionAddFieldConstraintDof(*section, idx[i], 0, nconst));
      PetscCall(PetscSectionAddConstraintDof(*section, idx[i], nconst));
    }
    PetscCall(ISRestoreIndices(points[bc], &idx));
  }
  PetscCall(PetscSectionSetFromOptions(*section));
  PetscCall(PetscSectionSetUp(*section));
  if (!nbc) PetscFunctionReturn(PETSC_SUCCESS);
  /* the field's constraint indices: DMPlexCreateSectionBCIndicesField(), over the vertices (the only points with
     dofs, so with constraints; at the others it sets nothing) */
  for (PetscInt v = vStart; v < vEnd; ++v) {
    PetscInt cdof;

    PetscCall(PetscSectionGetConstraintDof(*section, v, &cdof));
    max_cdof = PetscMax(max_cdof, cdof);
  }
  PetscCall(PetscMalloc1(PetscMax(max_cdof, ndof) + nc, &indices));
  for (PetscInt d = 0; d < max_cdof; ++d) indices[d] = -1;
  for (PetscInt v = vStart; v < vEnd; ++v) PetscCall(PetscSectionSetFieldConstraintIndices(*section, v, 0, indices));
  for (PetscInt bc = 0; bc < nbc; ++bc) {
    const PetscInt *idx, *comp = NULL;
    PetscInt        n, cnc     = -1;

    if (comps[bc]) {
      PetscCall(ISGetLocalSize(comps[bc], &cnc));
      PetscCall(ISGetIndices(comps[bc], &comp));
    }
    PetscCall(ISGetLocalSize(points[bc], &n));
    PetscCall(ISGetIndices(points[bc], &idx));
    for (PetscInt i = 0; i < n; ++i) {
      const PetscInt  p = idx[i];
      const PetscInt *find;
      PetscInt        fdof, fcdof, d;

      PetscCall(PetscSectionGetFieldDof(*section, p, 0, &fdof));
      if (!fdof) continue;
      if (cnc < 0) {
        for (d = 0; d < fdof; ++d) indices[d] = d;
        fcdof = fdof;
      } else {
        PetscCall(PetscSectionGetFieldConstraintDof(*section, p, 0, &fcdof));
        PetscCall(PetscSectionGetFieldConstraintIndices(*section, p, 0, &find));
        for (d = 0; d < fcdof; ++d) { /* the components of earlier conditions */
          if (find[d] < 0) break;
          indices[d] = find[d];
        }
        for (PetscInt j = 0; j < fdof / nc; ++j)
          for (PetscInt c = 0; c < cnc; ++c) indices[d++] = j * nc + comp[c];
        PetscCall(PetscSortRemoveDupsInt(&d, indices));
        for (PetscInt c = d; c < fcdof; ++c) indices[c] = -1;
        fcdof = d;
      }
      PetscCall(PetscSectionSetFieldConstraintDof(*section, p, 0, fcdof));
      PetscCall(PetscSectionSetFieldConstraintIndices(*section, p, 0, indices));
    }
    PetscCall(ISRestoreIndices(points[bc], &idx));
    if (comp) PetscCall(ISRestoreIndices(comps[bc], &comp));
  }
  /* the points' constraint indices: DMPlexCreateSectionBCIndices(), with one field (vertices only, as above) */
  for (PetscInt p = vStart; p < vEnd; ++p) {
    const PetscInt *find;
    PetscInt        cdof, fcdof;

    PetscCall(PetscSectionGetConstraintDof(*section, p, &cdof));
    if (!cdof) continue;
    PetscCall(PetscSectionGetFieldConstraintDof(*section, p, 0, &fcdof));
    PetscCall(PetscSectionGetFieldConstraintIndices(*section, p, 0, &find));
    for (PetscInt d = 0; d < fcdof; ++d) indices[d] = find[d];
    if (cdof != fcdof) PetscCall(PetscSectionSetConstraintDof(*section, p, fcdof));
    PetscCall(PetscSectionSetConstraintIndices(*section, p, indices));
  }
  PetscCall(PetscFree(indices));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The local section of dm's displacements of this degree, where P1/Q1 (the head of the file); check (-section_check):
   compared with PETSc's. */
PetscErrorCode SectionSetUpP1(DM dm, PetscInt degree, PetscBool check)
{
  PetscSection section, reference = NULL;
  PetscDS      ds;
  PetscFE      fe;
  PetscObject  disc;
  PetscClassId id;
  DMLabel      ct_label;
  IS          *points, *comps;
  PetscInt     nfields, dim, depth, nc, nbd, nbc = 0, ghosts;
  const char  *name;

  PetscFunctionBeginUser;
  PetscCall(DMGetNumFields(dm, &nfields));
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMPlexGetDepth(dm, &depth));
  PetscCall(DMPlexGetCellTypeLabel(dm, &ct_label));
  PetscCall(DMLabelGetStratumSize(ct_label, DM_POLYTOPE_FV_GHOST, &ghosts));
  if (nfields != 1 || degree != 1 || depth != dim || ghosts) PetscFunctionReturn(PETSC_SUCCESS); /* PETSc's */
  PetscCall(DMGetField(dm, 0, NULL, &disc));
  PetscCall(PetscObjectGetClassId(disc, &id));
  if (id != PETSCFE_CLASSID) PetscFunctionReturn(PETSC_SUCCESS);
  {
    PetscSection anchors;

    PetscCall(DMPlexGetAnchors(dm, &anchors, NULL));
    if (anchors) PetscFunctionReturn(PETSC_SUCCESS);
  }
  fe = (PetscFE)disc;
  if (check) {
    PetscCall(DMGetLocalSection(dm, &reference)); /* PETSc's, for the comparison below */
    PetscCall(PetscObjectReference((PetscObject)reference));
  }
  PetscCall(PetscFEGetNumComponents(fe, &nc));
  PetscCall(DMGetDS(dm, &ds));
  PetscCall(PetscDSGetNumBoundary(ds, &nbd));
  for (PetscInt bd = 0; bd < nbd; ++bd) { /* DMCompleteBCLabels_Internal(): each label of a condition, made closed */
    DMLabel  label, earlier;
    PetscInt k;

    PetscCall(PetscDSGetBoundary(ds, bd, NULL, NULL, NULL, &label, NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL));
    for (k = 0; k < bd; ++k) {
      PetscCall(PetscDSGetBoundary(ds, k, NULL, NULL, NULL, &earlier, NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL));
      if (earlier == label) break;
    }
    if (label && k == bd) PetscCall(DMPlexLabelComplete(dm, label));
  }
  PetscCall(PetscCalloc2(nbd, &points, nbd, &comps));
  for (PetscInt bd = 0; bd < nbd; ++bd) {
    PetscBool essential = PETSC_FALSE;

    PetscCall(SectionBoundaryPoints(dm, ds, bd, &essential, &points[nbc], &comps[nbc]));
    if (essential) ++nbc;
  }
  {
    const PetscInt *numdof;

    PetscCall(PetscFEGetNumDof(fe, &numdof));
    PetscCall(SectionBuild(dm, nc, numdof[0], nbc, points, comps, &section));
  }
  PetscCall(PetscObjectGetName((PetscObject)fe, &name)); /* "displacement" (ElasticitySetUpDiscretization()) */
  PetscCall(PetscSectionSetFieldName(section, 0, name));
  for (PetscInt bc = 0; bc < nbc; ++bc) {
    PetscCall(ISDestroy(&points[bc]));
    PetscCall(ISDestroy(&comps[bc]));
  }
  PetscCall(PetscFree2(points, comps));
  if (reference) {
    PetscBool same, all;

    PetscCall(PetscSectionCompare(section, reference, &same));
    PetscCallMPI(MPI_Allreduce(&same, &all, 1, MPIU_BOOL, MPI_LAND, PetscObjectComm((PetscObject)dm)));
    PetscCall(PetscPrintf(PetscObjectComm((PetscObject)dm), "  section check: the P1 section is %s DMCreateLocalSection()'s\n",
                          all ? "equal to" : "DIFFERENT from"));
    PetscCall(PetscSectionDestroy(&reference));
  }
  PetscCall(DMSetLocalSection(dm, section));
  PetscCall(PetscSectionDestroy(&section));
  PetscCall(SectionSetUpGlobalP1(dm, check)); /* src/discretization/section_global.c */
  PetscFunctionReturn(PETSC_SUCCESS);
}

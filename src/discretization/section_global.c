/* The global section and the section SF of the P1/Q1 section (src/discretization/section.c), built over the vertices, the only
   points with dofs. PETSc 3.18 builds both with several calls per mesh point (PetscSectionCreateGlobalSection(),
   PetscSFSetGraphSection()), of which a 2D mesh has 6 per vertex (a 3D one 26). These are PETSc's results, entry for
   entry, in the same order; -section_check builds PETSc's too and compares them (PetscSectionCompare(), and the SF's
   graph).
   One of PETSc 3.18's mirrors (docs/decisions.md, "PETSc 3.18's mirrors"). */
#include <petscsf.h>
#include "discretization.h"
#include "physics.h"

/* PetscSectionCreateGlobalSection(lsec, point SF, PETSC_FALSE, PETSC_FALSE): the vertices' dofs and constraints, every
   point's offset among the unconstrained dofs of the points before it, and the ghost points' negative dofs and offsets,
   -(dof + 1) and -(owner's offset + 1). The dofs of a point that is not a vertex are zero. */
static PetscErrorCode SectionCreateGlobalP1(DM dm, PetscSection lsec, PetscSection *gsec)
{
  MPI_Comm     comm = PetscObjectComm((PetscObject)dm);
  PetscSection gs, gfs, lfs;
  PetscSF      sf;
  PetscInt     pStart, pEnd, vStart, vEnd, nc, nroots, off = 0, goff = 0, *neg = NULL, *recv = NULL, *count;

  PetscFunctionBeginUser;
  PetscCall(DMGetPointSF(dm, &sf));
  PetscCall(PetscSectionGetChart(lsec, &pStart, &pEnd));
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  PetscCall(PetscSectionGetFieldComponents(lsec, 0, &nc));
  PetscCall(PetscSectionCreate(comm, &gs));
  PetscCall(PetscSectionSetNumFields(gs, 1));
  PetscCall(PetscSectionSetChart(gs, pStart, pEnd));
  PetscCall(PetscSectionSetFieldComponents(gs, 0, nc));
  PetscCall(PetscSectionGetField(lsec, 0, &lfs)); /* the field's own sections: PetscSection*Field*() call them */
  PetscCall(PetscSectionGetField(gs, 0, &gfs));
  for (PetscInt v = vStart; v < vEnd; ++v) {
    PetscInt dof, cdof, fdof, fcdof;

    PetscCall(PetscSectionGetDof(lsec, v, &dof));
    PetscCall(PetscSectionGetConstraintDof(lsec, v, &cdof));
    PetscCall(PetscSectionGetDof(lfs, v, &fdof));
    PetscCall(PetscSectionGetConstraintDof(lfs, v, &fcdof));
    PetscCall(PetscSectionSetDof(gs, v, dof));
    PetscCall(PetscSectionSetDof(gfs, v, fdof));
    if (cdof > 0) PetscCall(PetscSectionSetConstraintDof(gs, v, cdof));
    if (fcdof > 0) PetscCall(PetscSectionSetConstraintDof(gfs, v, fcdof));
  }
  PetscCall(PetscSectionSetIncludesConstraints(gs, PETSC_FALSE));
  PetscCall(PetscSectionSetIncludesConstraints(gfs, PETSC_FALSE));
  PetscCall(PetscSectionSetUpBC(gs)); /* the constraints' layout, as PETSc's: no PetscSectionSetUp(), the offsets are set below */
  PetscCall(PetscSectionSetUpBC(gfs));
  for (PetscInt v = vStart; v < vEnd; ++v) { /* the constraint indices, the point's and the field's, while the dofs are positive */
    const PetscInt *idx;
    PetscInt        cdof, fcdof;

    PetscCall(PetscSectionGetConstraintDof(lsec, v, &cdof));
    if (cdof > 0) {
      PetscCall(PetscSectionGetConstraintIndices(lsec, v, &idx));
      PetscCall(PetscSectionSetConstraintIndices(gs, v, idx));
    }
    PetscCall(PetscSectionGetConstraintDof(lfs, v, &fcdof));
    if (fcdof > 0) {
      PetscCall(PetscSectionGetConstraintIndices(lfs, v, &idx));
      PetscCall(PetscSectionSetConstraintIndices(gfs, v, idx));
    }
  }
  PetscCall(PetscSFGetGraph(sf, &nroots, NULL, NULL, NULL));
  if (nroots >= 0) { /* a graph: the ghost points get their owners' dofs, negative */
    PetscCheck(nroots >= pEnd, PETSC_COMM_SELF, PETSC_ERR_ARG_SIZ, "Point SF roots %" PetscInt_FMT " < chart end %" PetscInt_FMT, nroots, pEnd);
    PetscCall(PetscCalloc2(nroots, &neg, nroots, &recv));
    for (PetscInt p = pStart; p < pEnd; ++p) neg[p] = -1;
    for (PetscInt v = vStart; v < vEnd; ++v) {
      PetscInt dof;

      PetscCall(PetscSectionGetDof(lsec, v, &dof));
      neg[v] = -(dof + 1);
    }
    PetscCall(PetscSFBcastBegin(sf, MPIU_INT, neg, recv, MPI_REPLACE));
    PetscCall(PetscSFBcastEnd(sf, MPIU_INT, neg, recv, MPI_REPLACE));
    for (PetscInt p = pStart; p < pEnd; ++p) {
      PetscInt dof;

      if (recv[p] >= 0) continue;
      PetscCall(PetscSectionGetDof(lsec, p, &dof));
      PetscCheck(-(recv[p] + 1) == dof, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG,
                 "Point %" PetscInt_FMT " has %" PetscInt_FMT " dofs on its owner, %" PetscInt_FMT " here", p, -(recv[p] + 1), dof);
      PetscCall(PetscSectionSetDof(gs, p, recv[p]));
    }
  }
  /* the offsets: a point's is the count of unconstrained owned dofs before it, on this rank and the ranks before it;
     only vertices have dofs, and a depth stratum is a range of points, so a point before the vertices has the rank's
     first offset and a point after them its end */
  PetscCall(PetscMalloc1(vEnd - vStart, &count));
  for (PetscInt v = vStart; v < vEnd; ++v) {
    PetscInt dof, cdof;

    PetscCall(PetscSectionGetDof(gs, v, &dof));
    PetscCall(PetscSectionGetConstraintDof(lsec, v, &cdof));
    count[v - vStart] = dof > 0 ? dof - cdof : 0;
    off += count[v - vStart];
  }
  PetscCallMPI(MPI_Scan(&off, &goff, 1, MPIU_INT, MPI_SUM, comm));
  goff -= off;
  off = goff;
  for (PetscInt p = pStart; p < pEnd; ++p) { /* the field's offsets are the point's: one field */
    const PetscInt o = p < vStart ? goff : off;

    PetscCall(PetscSectionSetOffset(gs, p, o));
    PetscCall(PetscSectionSetOffset(gfs, p, o));
    if (neg) neg[p] = -(o + 1);
    if (p >= vStart && p < vEnd) off += count[p - vStart];
  }
  PetscCall(PetscFree(count));
  if (neg) { /* the ghost points' offsets, their owners' negative, and their field dofs negative */
    PetscCall(PetscArrayzero(recv, nroots));
    PetscCall(PetscSFBcastBegin(sf, MPIU_INT, neg, recv, MPI_REPLACE));
    PetscCall(PetscSFBcastEnd(sf, MPIU_INT, neg, recv, MPI_REPLACE));
    for (PetscInt p = pStart; p < pEnd; ++p) {
      PetscInt fdof = 0;

      if (recv[p] >= 0) continue;
      PetscCall(PetscSectionSetOffset(gs, p, recv[p]));
      PetscCall(PetscSectionSetOffset(gfs, p, recv[p]));
      if (p >= vStart && p < vEnd) PetscCall(PetscSectionGetDof(lfs, p, &fdof));
      PetscCall(PetscSectionSetDof(gfs, p, -(fdof + 1)));
    }
  }
  PetscCall(PetscFree2(neg, recv));
  *gsec = gs;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* PetscSFSetGraphSection(sf, lsec, gsec): a leaf for each unconstrained local dof, in point order, its root the dof's
   owner and its place among the owner's unconstrained dofs. Only vertices have dofs. */
static PetscErrorCode SectionCreateSFP1(DM dm, PetscSection lsec, PetscSection gsec, PetscSF *sf)
{
  MPI_Comm        comm = PetscObjectComm((PetscObject)dm);
  PetscLayout     layout;
  const PetscInt *ranges;
  PetscInt        vStart, vEnd, nroots, nleaves = 0, l = 0, *local;
  PetscSFNode    *remote;
  PetscMPIInt     size, rank;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  PetscCall(PetscSectionGetConstrainedStorageSize(gsec, &nroots));
  PetscCall(PetscLayoutCreate(comm, &layout));
  PetscCall(PetscLayoutSetBlockSize(layout, 1));
  PetscCall(PetscLayoutSetLocalSize(layout, nroots));
  PetscCall(PetscLayoutSetUp(layout));
  PetscCall(PetscLayoutGetRanges(layout, &ranges));
  for (PetscInt v = vStart; v < vEnd; ++v) {
    PetscInt dof, cdof;

    PetscCall(PetscSectionGetDof(lsec, v, &dof));
    PetscCall(PetscSectionGetConstraintDof(lsec, v, &cdof));
    nleaves += dof - cdof;
  }
  PetscCall(PetscMalloc1(nleaves, &local));
  PetscCall(PetscMalloc1(nleaves, &remote));
  for (PetscInt v = vStart; v < vEnd; ++v) {
    const PetscInt *cind;
    PetscInt        dof, cdof, off, gdof, goff, d, c;

    PetscCall(PetscSectionGetDof(lsec, v, &dof));
    PetscCall(PetscSectionGetOffset(lsec, v, &off));
    PetscCall(PetscSectionGetConstraintDof(lsec, v, &cdof));
    PetscCall(PetscSectionGetConstraintIndices(lsec, v, &cind));
    PetscCall(PetscSectionGetDof(gsec, v, &gdof));
    PetscCall(PetscSectionGetOffset(gsec, v, &goff));
    for (d = 0, c = 0; d < dof; ++d) {
      if (c < cdof && cind[c] == d) {
        ++c;
        continue;
      }
      local[l + d - c] = off + d;
    }
    for (d = 0; d < dof - cdof; ++d, ++l) {
      const PetscInt g = gdof < 0 ? -(goff + 1) + d : goff + d;
      PetscInt       r = rank;

      if (gdof < 0) {
        PetscCall(PetscFindInt(g, size + 1, ranges, &r));
        if (r < 0) r = -(r + 2);
        PetscCheck(r >= 0 && r < size, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "Vertex %" PetscInt_FMT " mapped to invalid rank %" PetscInt_FMT, v,
                   r);
      }
      remote[l].rank  = r;
      remote[l].index = g - ranges[r];
    }
  }
  PetscCall(PetscLayoutDestroy(&layout));
  PetscCall(PetscSFCreate(comm, sf));
  PetscCall(PetscSFSetGraph(*sf, nroots, nleaves, local, PETSC_OWN_POINTER, remote, PETSC_OWN_POINTER));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Whether two SFs have the same graph, on every rank. */
static PetscErrorCode SectionSFCompare(PetscSF a, PetscSF b, PetscBool *same)
{
  const PetscInt    *la, *lb;
  const PetscSFNode *ra, *rb;
  PetscInt           na, nb, ma, mb;
  PetscBool          local = PETSC_TRUE;

  PetscFunctionBeginUser;
  PetscCall(PetscSFGetGraph(a, &na, &ma, &la, &ra));
  PetscCall(PetscSFGetGraph(b, &nb, &mb, &lb, &rb));
  if (na != nb || ma != mb) local = PETSC_FALSE;
  for (PetscInt i = 0; local && i < ma; ++i) {
    const PetscInt ia = la ? la[i] : i, ib = lb ? lb[i] : i;

    local = (PetscBool)(ia == ib && ra[i].rank == rb[i].rank && ra[i].index == rb[i].index);
  }
  PetscCallMPI(MPI_Allreduce(&local, same, 1, MPIU_BOOL, MPI_LAND, PetscObjectComm((PetscObject)a)));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode SectionSetUpGlobalP1(DM dm, PetscBool check)
{
  PetscSection lsec, gsec;
  PetscSF      sf;

  PetscFunctionBeginUser;
  PetscCall(DMGetLocalSection(dm, &lsec));
  PetscCall(SectionCreateGlobalP1(dm, lsec, &gsec));
  PetscCall(SectionCreateSFP1(dm, lsec, gsec, &sf));
  if (check) {
    PetscSection ref;
    PetscSF      point_sf, ref_sf;
    PetscBool    same_section, same_sf, incl, fincl;
    PetscSection gfs;

    PetscCall(DMGetPointSF(dm, &point_sf));
    PetscCall(PetscSectionCreateGlobalSection(lsec, point_sf, PETSC_FALSE, PETSC_FALSE, &ref));
    PetscCall(PetscSectionCompare(gsec, ref, &same_section));
    PetscCall(PetscSectionGetIncludesConstraints(gsec, &incl));
    PetscCall(PetscSectionGetField(gsec, 0, &gfs));
    PetscCall(PetscSectionGetIncludesConstraints(gfs, &fincl));
    same_section = (PetscBool)(same_section && !incl && !fincl);
    PetscCall(PetscSFCreate(PetscObjectComm((PetscObject)dm), &ref_sf));
    PetscCall(PetscSFSetGraphSection(ref_sf, lsec, ref));
    PetscCall(SectionSFCompare(sf, ref_sf, &same_sf));
    PetscCall(
        PetscPrintf(PetscObjectComm((PetscObject)dm),
                    "  section check: the global section is %s PetscSectionCreateGlobalSection()'s, the section SF %s PetscSFSetGraphSection()'s\n",
                    same_section ? "equal to" : "DIFFERENT from", same_sf ? "equal to" : "DIFFERENT from"));
    PetscCall(PetscSFDestroy(&ref_sf));
    PetscCall(PetscSectionDestroy(&ref));
  }
  PetscCall(DMSetGlobalSection(dm, gsec));
  PetscCall(DMSetSectionSF(dm, sf));
  PetscCall(PetscSectionDestroy(&gsec));
  PetscCall(PetscSFDestroy(&sf));
  PetscFunctionReturn(PETSC_SUCCESS);
}

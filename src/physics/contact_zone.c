/* The contact zone's size after the solve: its width on a 2D Gamma_C, its area on a 3D one.

   A count of the active nodes' areas would change by a whole face whenever a node enters, so the size would not
   converge smoothly with h and its error could not be extrapolated (src/estimate/bars.c). Instead each vertex of
   Gamma_C gets a signed value s, negative where the body is open (-s is the gap) and positive where it is in contact,
   and the zone is the part of Gamma_C where the linear interpolant of s is positive, measured exactly face by face (the
   zero crossing on an edge, the clipped part of a triangle; a quadrilateral as two triangles):
     the penalty method (and no contact): s = u_n - g, positive where the penalty force acts;
     SNESVI, where u_n = g on the whole active set: s = u_n - g + (h_v / E) p, with h_v = (lumped boundary mass)^(1/(dim-1))
     the local mesh size, so that the pressure marks the contact side. */
#include <petscsf.h>
#include "physics.h"

/* The part of a face of measure area where the linear function of the vertex values s[] (2 or 3 of them) is positive. */
static PetscReal PositiveMeasure(PetscInt n, const PetscReal s[], PetscReal area)
{
  PetscInt npos = 0, one = -1, other[2], k = 0;

  for (PetscInt i = 0; i < n; ++i) npos += s[i] > 0.0;
  if (npos == 0) return 0.0;
  if (npos == n) return area;
  if (n == 2) {
    const PetscReal sp = PetscMax(s[0], s[1]), sn = PetscMin(s[0], s[1]);
    return area * sp / (sp - sn);
  }
  for (PetscInt i = 0; i < 3; ++i) /* the vertex alone on its side, and the two others */
    if ((npos == 1) == (s[i] > 0.0))
      one = i;
    else
      other[k++] = i;
  {
    const PetscReal corner = s[one] * s[one] / ((s[one] - s[other[0]]) * (s[one] - s[other[1]])); /* its corner triangle's part */
    return area * (npos == 1 ? corner : 1.0 - corner);
  }
}

static PetscReal TriangleArea(const PetscReal a[], const PetscReal b[], const PetscReal c[])
{
  const PetscReal u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const PetscReal w[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};

  return 0.5 * PetscSqrtReal(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
}

PetscErrorCode PostprocessContactSize(DM dm, AppCtx *user, Vec u, PetscReal *size)
{
  const ContactSet  *cs;
  const PetscReal    E = user->opt->material.young_modulus;
  PetscInt           dim, pStart, pEnd, vStart, vEnd, nroots;
  PetscReal         *s, local = 0.0;
  PetscSF            sf;
  DM                 cdm;
  PetscSection       csec;
  Vec                coords;
  const PetscScalar *x, *xc;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(ContactGetSet(user->contact, &cs));
  PetscCall(DMPlexGetChart(dm, &pStart, &pEnd));
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  PetscCall(PetscCalloc1(pEnd - pStart, &s)); /* 0 at a node of Gamma_C with no free component (clamped) */
  PetscCall(VecGetArrayRead(u, &x));
  for (PetscInt i = 0; i < cs->n; ++i) {
    if (!cs->is_vertex[i]) continue;
    s[cs->point[i] - pStart] = ContactNodePenetration(cs, dim, i, x);
    if (ContactHasBounds(user->contact)) s[cs->point[i] - pStart] += PetscPowReal(cs->weight[i], 1.0 / (dim - 1)) / E * cs->pressure[i];
  }
  PetscCall(VecRestoreArrayRead(u, &x));
  PetscCall(DMGetPointSF(dm, &sf)); /* the owners' values to the ranks that share the vertex */
  PetscCall(PetscSFGetGraph(sf, &nroots, NULL, NULL, NULL));
  if (nroots >= 0) {
    PetscCall(PetscSFBcastBegin(sf, MPIU_REAL, s, s, MPI_REPLACE));
    PetscCall(PetscSFBcastEnd(sf, MPIU_REAL, s, s, MPI_REPLACE));
  }
  PetscCall(DMGetCoordinateDM(dm, &cdm));
  PetscCall(DMGetLocalSection(cdm, &csec));
  PetscCall(DMGetCoordinatesLocal(dm, &coords));
  PetscCall(VecGetArrayRead(coords, &xc));
  for (PetscInt k = 0; k < user->scene.bcs.ncontact; ++k) {
    PetscInt *faces, nf;

    PetscCall(MeshGetBoundaryFaces(dm, user->scene.bcs.contact_ids[k], &nf, &faces));
    for (PetscInt i = 0; i < nf; ++i) {
      PetscInt *cl = NULL, ncl, nv = 0, ns;
      PetscReal X[4][3] = {{0.0}}, sv[4];

      PetscCall(DMPlexGetSupportSize(dm, faces[i], &ns));
      if (ns != 1) continue; /* not a boundary face */
      PetscCall(DMPlexGetTransitiveClosure(dm, faces[i], PETSC_TRUE, &ncl, &cl));
      for (PetscInt j = 0; j < ncl && nv < 4; ++j) {
        const PetscInt p = cl[2 * j];
        PetscInt       off;

        if (p < vStart || p >= vEnd) continue;
        PetscCall(PetscSectionGetOffset(csec, p, &off));
        for (PetscInt d = 0; d < dim; ++d) X[nv][d] = PetscRealPart(xc[off + d]);
        sv[nv++] = s[p - pStart];
      }
      PetscCall(DMPlexRestoreTransitiveClosure(dm, faces[i], PETSC_TRUE, &ncl, &cl));
      if (dim == 2) {
        const PetscReal len = PetscSqrtReal(PetscSqr(X[1][0] - X[0][0]) + PetscSqr(X[1][1] - X[0][1]));

        local += PositiveMeasure(2, sv, len);
      } else { /* a triangle, or a quadrilateral as two */
        const PetscReal t0[3] = {sv[0], sv[1], sv[2]};

        local += PositiveMeasure(3, t0, TriangleArea(X[0], X[1], X[2]));
        if (nv == 4) {
          const PetscReal t1[3] = {sv[0], sv[2], sv[3]};

          local += PositiveMeasure(3, t1, TriangleArea(X[0], X[2], X[3]));
        }
      }
    }
    PetscCall(PetscFree(faces));
  }
  PetscCall(VecRestoreArrayRead(coords, &xc));
  PetscCall(PetscFree(s));
  PetscCall(MPIU_Allreduce(&local, size, 1, MPIU_REAL, MPIU_SUM, PetscObjectComm((PetscObject)dm)));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The contact zone's size after the solve: its width on a 2D Gamma_C, its area on a 3D one.

   A count of the active nodes' areas would change by a whole face whenever a node enters, so the size would not
   converge smoothly with h and its error could not be extrapolated (src/estimate/bars.c). Instead each vertex of
   Gamma_C gets a signed value s, negative where the body is open (-s is the gap) and positive where it is in contact,
   and the zone is the part of Gamma_C where the linear interpolant of s is positive, measured exactly face by face (the
   zero crossing on an edge, the clipped part of a triangle; a quadrilateral as two triangles), with
     s = u_n - g + (h_v / E) p,
   h_v = (lumped boundary mass)^(1/(dim-1)) the local mesh size and p the nodal pressure (the force the method exerts at
   the node over its lumped area), so that the pressure marks the contact side:
     SNESVI holds u_n = g on the whole active set, where u_n - g alone is 0;
     the Gauss rule's penalty acts at the quadrature points, and at small eps / h its nodal u_n - g oscillates and is
     negative at nodes that carry force (the default square at eps = h/100 measured 0.416 from u_n - g alone, 0.438
     with the pressure, as the nodal rule and SNESVI do; a coarse Hertz indenter mesh at eps = h/40, 0);
     the nodal rule has p = (u_n - g)_+ / eps at the node, so that s has the sign of u_n - g, scaled where it is positive.

   The zone's edge is a free boundary, which P1 resolves to about a cell: the discrete exact contact ends at an active
   node, so its size moves by whole faces as h falls (a staircase, not a power of h). The band along the edge, the measure
   of the strip one cell wide that the edge crosses (the length of each face the edge cuts in 2D; the edge's length in
   each cut triangle times the triangle's diameter in 3D), is that resolution: the error bars of the size take it as
   the floor of their mesh part (src/estimate/bars.c). */
#include <petscsf.h>
#include "physics.h"

/* Whether the linear function of the vertex values s[] changes sign strictly on the face (a 0 at a clamped node is no edge). */
static PetscBool Crossed(PetscInt n, const PetscReal s[])
{
  PetscBool pos = PETSC_FALSE, neg = PETSC_FALSE;

  for (PetscInt i = 0; i < n; ++i) {
    pos = (PetscBool)(pos || s[i] > 0.0);
    neg = (PetscBool)(neg || s[i] < 0.0);
  }
  return (PetscBool)(pos && neg);
}

static PetscReal Distance(const PetscReal a[], const PetscReal b[])
{
  return PetscSqrtReal(PetscSqr(a[0] - b[0]) + PetscSqr(a[1] - b[1]) + PetscSqr(a[2] - b[2]));
}

/* The band of a triangle (X, s) that the zero line of s crosses: the line's length in it times its diameter. */
static PetscReal TriangleBand(PetscReal X[][3], const PetscInt v[3], const PetscReal s[])
{
  PetscReal pts[2][3];
  PetscInt  k = 0;

  if (!Crossed(3, s)) return 0.0;
  for (PetscInt e = 0; e < 3 && k < 2; ++e) { /* the zero's points on the edges whose ends have strictly opposite signs */
    const PetscInt i = e, j = (e + 1) % 3;

    if (s[i] * s[j] < 0.0) {
      const PetscReal t = s[i] / (s[i] - s[j]);

      for (PetscInt d = 0; d < 3; ++d) pts[k][d] = X[v[i]][d] + t * (X[v[j]][d] - X[v[i]][d]);
      k++;
    } else if (s[i] == 0.0) {
      for (PetscInt d = 0; d < 3; ++d) pts[k][d] = X[v[i]][d];
      k++;
    }
  }
  if (k < 2) return 0.0;
  return Distance(pts[0], pts[1]) * PetscMax(PetscMax(Distance(X[v[0]], X[v[1]]), Distance(X[v[1]], X[v[2]])), Distance(X[v[0]], X[v[2]]));
}

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

/* The owners' values at the chart's points to the ranks that share them. */
static PetscErrorCode ShareValues(DM dm, PetscReal v[])
{
  PetscSF  sf;
  PetscInt nroots;

  PetscFunctionBeginUser;
  PetscCall(DMGetPointSF(dm, &sf));
  PetscCall(PetscSFGetGraph(sf, &nroots, NULL, NULL, NULL));
  if (nroots >= 0) {
    PetscCall(PetscSFBcastBegin(sf, MPIU_REAL, v, v, MPI_REPLACE));
    PetscCall(PetscSFBcastEnd(sf, MPIU_REAL, v, v, MPI_REPLACE));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Each vertex's s (the head of the file, E the material's Young modulus) at the chart's points, 0 off Gamma_C, the same
   on every rank that shares it. */
static PetscErrorCode ZoneValues(DM dm, Contact contact, const Material *mat, Vec u, PetscReal **s)
{
  const ContactSet  *cs;
  const PetscReal    E = mat->young_modulus;
  PetscInt           dim, pStart, pEnd;
  const PetscScalar *x;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(ContactGetSet(contact, &cs));
  PetscCall(DMPlexGetChart(dm, &pStart, &pEnd));
  PetscCall(PetscCalloc1(pEnd - pStart, s)); /* 0 at a node of Gamma_C with no free component (clamped) */
  PetscCall(VecGetArrayRead(u, &x));
  for (PetscInt i = 0; i < cs->n; ++i) {
    if (!cs->is_vertex[i]) continue;
    (*s)[cs->point[i] - pStart] = ContactNodePenetration(cs, dim, i, x);
    (*s)[cs->point[i] - pStart] += PetscPowReal(cs->weight[i], 1.0 / (dim - 1)) / E * cs->pressure[i];
  }
  PetscCall(VecRestoreArrayRead(u, &x));
  PetscCall(ShareValues(dm, *s));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* A boundary face's vertices: their coordinates X (NULL: not wanted) and their values sv of s, nv of them. */
static PetscErrorCode FaceVertices(DM dm, PetscInt face, const PetscReal s[], PetscReal X[][3], PetscReal sv[], PetscInt *nv)
{
  PetscInt          *cl = NULL, ncl, dim, pStart, vStart, vEnd;
  DM                 cdm;
  PetscSection       csec;
  Vec                coords;
  const PetscScalar *xc = NULL;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMPlexGetChart(dm, &pStart, NULL));
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  if (X) {
    PetscCall(DMGetCoordinateDM(dm, &cdm));
    PetscCall(DMGetLocalSection(cdm, &csec));
    PetscCall(DMGetCoordinatesLocal(dm, &coords));
    PetscCall(VecGetArrayRead(coords, &xc));
  }
  *nv = 0;
  PetscCall(DMPlexGetTransitiveClosure(dm, face, PETSC_TRUE, &ncl, &cl));
  for (PetscInt j = 0; j < ncl && *nv < 4; ++j) {
    const PetscInt p = cl[2 * j];

    if (p < vStart || p >= vEnd) continue;
    if (X) {
      PetscInt off;

      PetscCall(PetscSectionGetOffset(csec, p, &off));
      for (PetscInt d = 0; d < dim; ++d) X[*nv][d] = PetscRealPart(xc[off + d]);
    }
    sv[(*nv)++] = s[p - pStart];
  }
  PetscCall(DMPlexRestoreTransitiveClosure(dm, face, PETSC_TRUE, &ncl, &cl));
  if (X) PetscCall(VecRestoreArrayRead(coords, &xc));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The boundary faces of Gamma_C (the contact face sets of bcs) on this rank, over its face sets in turn (*faces
   allocated, PetscFree()). */
static PetscErrorCode GammaCFaces(DM dm, const BoundarySet *bcs, PetscInt *n, PetscInt **faces)
{
  PetscFunctionBeginUser;
  *n = 0;
  PetscCall(PetscMalloc1(1, faces));
  for (PetscInt k = 0; k < bcs->ncontact; ++k) {
    PetscInt *set, nf;

    PetscCall(MeshGetBoundaryFaces(dm, bcs->contact_ids[k], &nf, &set));
    PetscCall(PetscRealloc(sizeof(PetscInt) * (*n + nf + 1), faces));
    for (PetscInt i = 0; i < nf; ++i) {
      PetscInt ns;

      PetscCall(DMPlexGetSupportSize(dm, set[i], &ns));
      if (ns == 1) (*faces)[(*n)++] = set[i]; /* a boundary face */
    }
    PetscCall(PetscFree(set));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The zone's size and its band (the head of the file) of the solution u with the contact on Gamma_C of bcs, in the
   material, on every rank. */
PetscErrorCode PostprocessContactSize(DM dm, Contact contact, const BoundarySet *bcs, const Material *mat, Vec u, PetscReal *size, PetscReal *band)
{
  PetscInt   dim, *faces, nf;
  PetscReal *s, local[2] = {0.0, 0.0}, global[2];

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(ZoneValues(dm, contact, mat, u, &s));
  PetscCall(GammaCFaces(dm, bcs, &nf, &faces));
  for (PetscInt i = 0; i < nf; ++i) {
    PetscInt  nv;
    PetscReal X[4][3] = {{0.0}}, sv[4];

    PetscCall(FaceVertices(dm, faces[i], s, X, sv, &nv));
    if (dim == 2) {
      const PetscReal len = PetscSqrtReal(PetscSqr(X[1][0] - X[0][0]) + PetscSqr(X[1][1] - X[0][1]));

      local[0] += PositiveMeasure(2, sv, len);
      if (Crossed(2, sv)) local[1] += len;
    } else { /* a triangle, or a quadrilateral as two */
      const PetscReal t0[3] = {sv[0], sv[1], sv[2]};
      const PetscInt  v0[3] = {0, 1, 2};

      local[0] += PositiveMeasure(3, t0, TriangleArea(X[0], X[1], X[2]));
      local[1] += TriangleBand(X, v0, t0);
      if (nv == 4) {
        const PetscReal t1[3] = {sv[0], sv[2], sv[3]};
        const PetscInt  v1[3] = {0, 2, 3};

        local[0] += PositiveMeasure(3, t1, TriangleArea(X[0], X[2], X[3]));
        local[1] += TriangleBand(X, v1, t1);
      }
    }
  }
  PetscCall(PetscFree(faces));
  PetscCall(PetscFree(s));
  PetscCall(MPIU_Allreduce(local, global, 2, MPIU_REAL, MPIU_SUM, PetscObjectComm((PetscObject)dm)));
  *size = global[0];
  *band = global[1];
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The faces of Gamma_C that the zone's edge crosses, the band's (on this rank; *faces allocated, PetscFree()), for the
   same inputs as PostprocessContactSize(). */
PetscErrorCode PostprocessContactEdgeFaces(DM dm, Contact contact, const BoundarySet *bcs, const Material *mat, Vec u, PetscInt *n, PetscInt **edge)
{
  PetscReal *s;
  PetscInt   nf;

  PetscFunctionBeginUser;
  PetscCall(ZoneValues(dm, contact, mat, u, &s));
  PetscCall(GammaCFaces(dm, bcs, &nf, edge));
  *n = 0;
  for (PetscInt i = 0; i < nf; ++i) { /* kept in place */
    PetscInt  nv;
    PetscReal sv[4];

    PetscCall(FaceVertices(dm, (*edge)[i], s, NULL, sv, &nv));
    if (Crossed(nv, sv)) (*edge)[(*n)++] = (*edge)[i];
  }
  PetscCall(PetscFree(s));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The largest pressure's resolution: the largest change of the nodal pressure from a node that carries the largest,
   pressure_max, to the other vertices of its faces of Gamma_C, over all ranks (0 without contact). The nodal maximum
   stands for the largest pressure of the cells around its node, across which the discrete pressure changes by this
   much; where the maximum sits at a kink or an end of the profile (the manufactured solution's, at the end of Gamma_C,
   changes there at the order h) the cycles' differences do not see that error while the refinement goes elsewhere,
   and the largest pressure's bar takes the step as its floor (src/estimate/cycle_bars.c), as the size's takes its band.
   The nodal pressure of the contact's set, on the faces of Gamma_C of bcs. */
PetscErrorCode PostprocessPressureStep(DM dm, Contact contact, const BoundarySet *bcs, PetscReal pressure_max, PetscReal *step)
{
  const ContactSet *cs;
  PetscInt          pStart, pEnd, nf, *faces;
  PetscReal        *p, local = 0.0;

  PetscFunctionBeginUser;
  PetscCall(ContactGetSet(contact, &cs));
  PetscCall(DMPlexGetChart(dm, &pStart, &pEnd));
  PetscCall(PetscCalloc1(pEnd - pStart, &p));
  for (PetscInt i = 0; i < cs->n; ++i)
    if (cs->is_vertex[i]) p[cs->point[i] - pStart] = cs->pressure[i];
  PetscCall(ShareValues(dm, p));
  PetscCall(GammaCFaces(dm, bcs, &nf, &faces));
  for (PetscInt i = 0; i < nf && pressure_max > 0.0; ++i) {
    PetscInt  nv;
    PetscReal pv[4];
    PetscBool top = PETSC_FALSE;

    PetscCall(FaceVertices(dm, faces[i], p, NULL, pv, &nv));
    for (PetscInt v = 0; v < nv; ++v) top = (PetscBool)(top || pv[v] == pressure_max);
    for (PetscInt v = 0; v < nv && top; ++v) local = PetscMax(local, pressure_max - pv[v]);
  }
  PetscCall(PetscFree(faces));
  PetscCall(PetscFree(p));
  PetscCall(MPIU_Allreduce(&local, step, 1, MPIU_REAL, MPIU_MAX, PetscObjectComm((PetscObject)dm)));
  PetscFunctionReturn(PETSC_SUCCESS);
}

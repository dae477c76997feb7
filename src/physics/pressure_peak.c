/* The largest contact pressure recovered from the nodal pressures around it: pressure_peak.

   The nodal pressure (the node's reaction over its lumped area, ContactPostProcess()) scatters from node to node on an
   irregular triangulation of Gamma_C by more than its error at the profile's top. On tetrahedra the scatter is the
   P1 traction's: with one eps over Gamma_C it falls with h, but not with the number of unknowns that the marking puts
   at the zone's edge, and the largest nodal value picks the scatter's upper tail. A local eps that follows each cell's
   diameter adds its own jumps (MeshSetContactCellSizes()). docs/decisions.md, "The recovered peak", has the numbers.

   The peak averages the scatter out as superconvergent patch recovery does for stresses (Zienkiewicz and Zhu): the
   quadratic polynomial in the tangent plane of Gamma_C at the largest nodal pressure's node (the top) that fits, by
   least squares, the pressures of the nodes in contact around it: the PEAK_NODES nearest (about two rings of a
   triangulated surface, one side of the top in 2D), and all those within PEAK_ZONE of the top's distance to the zone's
   edge (the nearest vertex of Gamma_C that carries no pressure). The peak is the fit's largest value where it has one
   within the patch, and otherwise its value at the top (the end of a steep profile, as the manufactured solution's).
   - At its largest, not at the top: the top is where the scatter put it, off the profile's maximum, where the profile
     is lower.
   - A patch that grows with the zone: a fixed number of nodes covers less of the profile as h falls, and its standard
     error stays; all the nodes within a fraction of the zone average more of them as the mesh refines. Its truncation,
     the profile's quartic term, is what bounds PEAK_ZONE.
   The fit's own standard error at the point it is evaluated, phi the monomials there,
     se^2 = s^2 phi^T (D^T D)^{-1} phi,  s^2 = |p - D c|^2 / (K - m),
   (D the K x m design matrix of the monomials, c the coefficients; at the fit's largest its gradient vanishes, so
   that the point's own scatter adds nothing to first order) says how well the scatter is averaged, and the
   fit's change from the top to the top's neighbours (the nodes within PEAK_RING times the nearest one's distance) how
   well the mesh resolves the profile there, as the nodal step does (PostprocessPressureStep()): where the maximum sits
   at a steep end of the profile (the manufactured solution's, at the end of Gamma_C) the step is the larger. The step
   counts beyond PEAK_SIGNIFICANT times its own standard deviation (that of the linear functional c . (phi_j - phi_top)
   of the coefficients): at a smooth top the fitted slope is the scatter's, which the standard error already holds. The
   larger of the two is the peak's resolution, which its -accuracy bar takes as its deviation (src/estimate/cycle_bars.c).
   With fewer nodes in contact than twice the monomials the peak is the nodal maximum and its resolution the nodal step.

   Every rank computes the same fit from the same nodes: each rank's largest nodal pressure is gathered on every rank,
   the largest of them is the top, the zone's edge is the nearest of the ranks' own, and each rank's own nodes of the
   patch are gathered too: its PEAK_NODES nearest the top and those within the zone's fraction, among which are the
   patch's over all ranks (a node's position, normal and pressure each). The top and the patch are chosen by
   the pressures and positions alone, ties broken by the coordinates (pressures within PEAK_TIE of the largest tie, and
   below PEAK_TIE of it a node carries none), and the fit sums its nodes in the order of their distance, so that the
   peak does not depend on the partition, or on the solve's last bits, beyond the pressures' own solver tolerance. */
#include "physics.h"

#define PEAK_NODES_2D 5      /* the top and two nodes on each side */
#define PEAK_NODES_3D 20     /* the top and about two rings of triangles around it */
#define PEAK_STRIDE 7        /* x[3], normal[3], p of each gathered node */
#define PEAK_RING 1.5        /* the top's neighbours: the nodes within this times the nearest one's distance */
#define PEAK_SIGNIFICANT 2.0 /* the fit's step counts beyond this many of its own standard deviations */
#define PEAK_ZONE 0.3        /* the patch reaches this fraction of the top's distance to the zone's edge */
#define PEAK_TIE 1e-6        /* pressures within this fraction of the largest tie (the coordinates decide); below it, none */

typedef struct {
  PetscReal dist; /* to the top */
  PetscReal x[3];
  PetscInt  i; /* its row */
} PeakNode;

/* By the distance to the top, ties by the coordinates: the same order whatever order the ranks gathered the nodes in. */
static int ComparePeakNodes(const void *a, const void *b)
{
  const PeakNode *x = (const PeakNode *)a, *y = (const PeakNode *)b;

  if (x->dist != y->dist) return x->dist < y->dist ? -1 : 1;
  for (PetscInt d = 0; d < 3; ++d)
    if (x->x[d] != y->x[d]) return x->x[d] < y->x[d] ? -1 : 1;
  return 0;
}

/* The vertices of this rank's contact set that carry a pressure above pmin (in_contact), or pmin or less (not), PEAK_STRIDE
   reals each. */
static PetscErrorCode LocalContactRows(DM dm, const ContactSet *cs, PetscInt dim, PetscReal pmin, PetscBool in_contact, PetscInt *n, PetscReal **rows)
{
  PetscSection       csec;
  Vec                coords;
  const PetscScalar *xc;

  PetscFunctionBeginUser;
  PetscCall(DMGetCoordinateSection(dm, &csec));
  PetscCall(DMGetCoordinatesLocal(dm, &coords));
  PetscCall(VecGetArrayRead(coords, &xc));
  PetscCall(PetscMalloc1(cs->n * PEAK_STRIDE + 1, rows));
  *n = 0;
  for (PetscInt i = 0; i < cs->n; ++i) {
    PetscInt   off;
    PetscReal *row = &(*rows)[*n * PEAK_STRIDE];

    if (!cs->is_vertex[i] || (PetscBool)(cs->pressure[i] > pmin) != in_contact) continue;
    PetscCall(PetscSectionGetOffset(csec, cs->point[i], &off));
    for (PetscInt d = 0; d < 3; ++d) {
      row[d]     = d < dim ? PetscRealPart(xc[off + d]) : 0.0;
      row[3 + d] = d < dim ? cs->normal[i * dim + d] : 0.0;
    }
    row[6] = cs->pressure[i];
    ++*n;
  }
  PetscCall(VecRestoreArrayRead(coords, &xc));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Every rank's n rows, in the order of the ranks, on every rank. */
static PetscErrorCode AllgatherRows(MPI_Comm comm, PetscInt n, const PetscReal rows[], PetscInt *total, PetscReal **all)
{
  PetscMPIInt size, count, *counts, *displs;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscCall(PetscMPIIntCast(n * PEAK_STRIDE, &count));
  PetscCall(PetscMalloc2(size, &counts, size + 1, &displs));
  PetscCallMPI(MPI_Allgather(&count, 1, MPI_INT, counts, 1, MPI_INT, comm));
  displs[0] = 0;
  for (PetscMPIInt r = 0; r < size; ++r) displs[r + 1] = displs[r] + counts[r];
  PetscCall(PetscMalloc1(displs[size] + 1, all));
  PetscCallMPI(MPI_Allgatherv(rows, count, MPIU_REAL, *all, counts, displs, MPIU_REAL, comm));
  *total = displs[size] / PEAK_STRIDE;
  PetscCall(PetscFree2(counts, displs));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Of the rows whose pressure is within PEAK_TIE of the largest, pmax, the one with the smallest coordinates; -1 without
   such rows. Two nodes whose pressures are equal but for round-off (the two sides of a symmetric top) are one tie, so
   that the top, and the fit around it, do not flip with the solve's last bits (the default square's 8 x 8 SNESVI run
   fitted at one side's node on 1 rank and at the other's on 2: 0.7157 and 0.7069). */
static PetscInt TopRow(PetscInt n, const PetscReal rows[], PetscReal pmax)
{
  PetscInt top = -1;

  for (PetscInt i = 0; i < n; ++i) {
    const PetscReal *ri    = &rows[i * PEAK_STRIDE];
    PetscBool        first = PETSC_FALSE;

    if (ri[6] < pmax - PEAK_TIE * PetscAbsReal(pmax)) continue;
    if (top < 0)
      first = PETSC_TRUE;
    else {
      const PetscReal *rt = &rows[top * PEAK_STRIDE];

      for (PetscInt d = 0; d < 3; ++d)
        if (ri[d] != rt[d]) {
          first = (PetscBool)(ri[d] < rt[d]);
          break;
        }
    }
    if (first) top = i;
  }
  return top;
}

/* The distance from a gathered node's row to top. */
static PetscReal RowDistance(const PetscReal row[], const PetscReal top[])
{
  PetscReal d2 = 0.0;

  for (PetscInt d = 0; d < 3; ++d) d2 += PetscSqr(row[d] - top[d]);
  return PetscSqrtReal(d2);
}

/* The rows in the order of their distance to top (ComparePeakNodes()). */
static PetscErrorCode SortByDistance(PetscInt n, const PetscReal rows[], const PetscReal top[], PeakNode **order)
{
  PetscFunctionBeginUser;
  PetscCall(PetscMalloc1(n + 1, order));
  for (PetscInt i = 0; i < n; ++i) {
    for (PetscInt d = 0; d < 3; ++d) (*order)[i].x[d] = rows[i * PEAK_STRIDE + d];
    (*order)[i].dist = RowDistance(&rows[i * PEAK_STRIDE], top);
    (*order)[i].i    = i;
  }
  qsort(*order, n, sizeof(**order), ComparePeakNodes);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Two unit vectors orthogonal to n and each other (3D), or one (2D): the tangent plane's coordinates. */
static void TangentBasis(PetscInt dim, const PetscReal n[], PetscReal t[2][3])
{
  if (dim == 2) {
    t[0][0] = -n[1];
    t[0][1] = n[0];
    t[0][2] = 0.0;
    return;
  }
  {
    PetscInt  k    = 0; /* the axis least along n */
    PetscReal e[3] = {0.0, 0.0, 0.0}, en, len = 0.0;

    for (PetscInt d = 1; d < 3; ++d)
      if (PetscAbsReal(n[d]) < PetscAbsReal(n[k])) k = d;
    e[k] = 1.0;
    en   = n[k];
    for (PetscInt d = 0; d < 3; ++d) {
      t[0][d] = e[d] - en * n[d];
      len += PetscSqr(t[0][d]);
    }
    for (PetscInt d = 0; d < 3; ++d) t[0][d] /= PetscSqrtReal(len);
    t[1][0] = n[1] * t[0][2] - n[2] * t[0][1];
    t[1][1] = n[2] * t[0][0] - n[0] * t[0][2];
    t[1][2] = n[0] * t[0][1] - n[1] * t[0][0];
  }
}

/* The monomials 1, s, s^2 (2D) or 1, s1, s2, s1^2, s1 s2, s2^2 (3D) at the tangent coordinates s. */
static void MonomialsAt(PetscInt dim, const PetscReal s[], PetscReal phi[])
{
  phi[0] = 1.0;
  phi[1] = s[0];
  if (dim == 2) {
    phi[2] = s[0] * s[0];
    return;
  }
  phi[2] = s[1];
  phi[3] = s[0] * s[0];
  phi[4] = s[0] * s[1];
  phi[5] = s[1] * s[1];
}

/* The monomials at the tangent coordinates s = (x - top) . t / rho of the point x. */
static void Monomials(PetscInt dim, const PetscReal t[2][3], const PetscReal top[], PetscReal rho, const PetscReal x[], PetscReal phi[])
{
  PetscReal s[2] = {0.0, 0.0};

  for (PetscInt a = 0; a < dim - 1; ++a)
    for (PetscInt d = 0; d < 3; ++d) s[a] += (x[d] - top[d]) * t[a][d] / rho;
  MonomialsAt(dim, s, phi);
}

/* The monomials at the fitted quadratic's largest value, where it has one within the patch (|s| <= 1: the Hessian
   negative definite, the stationary point s* = -H^{-1} g no farther from the top than the patch's farthest node), and
   otherwise at the top (s = 0): a profile's maximum that the fit interpolates, or the end of a steep one. */
static void MonomialsAtMaximum(PetscInt dim, const PetscReal c[], PetscReal phi[])
{
  PetscReal s[2] = {0.0, 0.0};

  if (dim == 2) {
    if (c[2] < 0.0) s[0] = -c[1] / (2.0 * c[2]);
  } else {
    const PetscReal det = 4.0 * c[3] * c[5] - c[4] * c[4]; /* H = [2 c3, c4; c4, 2 c5], g = (c1, c2) */

    if (c[3] < 0.0 && det > 0.0) {
      s[0] = -(2.0 * c[5] * c[1] - c[4] * c[2]) / det;
      s[1] = -(2.0 * c[3] * c[2] - c[4] * c[1]) / det;
    }
  }
  if (!(s[0] * s[0] + s[1] * s[1] <= 1.0)) s[0] = s[1] = 0.0;
  MonomialsAt(dim, s, phi);
}

/* The standard deviation of d . c, c the coefficients of LeastSquares(): (s2 d^T Ri Ri^T d)^(1/2). */
static PetscReal FunctionalDeviation(PetscInt m, const PetscReal Ri[6][6], PetscReal s2, const PetscReal d[])
{
  PetscReal sum = 0.0;

  for (PetscInt l = 0; l < m; ++l) {
    PetscReal e = 0.0;

    for (PetscInt i = 0; i <= l; ++i) e += Ri[i][l] * d[i];
    sum += PetscSqr(e);
  }
  return PetscSqrtReal(s2 * sum);
}

/* Least squares by modified Gram-Schmidt: A (k x m, row-major) = Q R, overwritten by Q; c = R^{-1} Q^T b, Ri = R^{-1}
   and *s2 the residual's variance |b - A c|^2 / (k - m), so that the covariance of c is s2 Ri Ri^T. PETSC_FALSE where
   a column depends on the others (a patch on one line in 3D). */
static PetscBool LeastSquares(PetscInt k, PetscInt m, PetscReal A[], const PetscReal b[], PetscReal c[], PetscReal Ri[6][6], PetscReal *s2)
{
  PetscReal R[6][6] = {{0.0}}, qb[6], rss = 0.0;

  for (PetscInt j = 0; j < m; ++j) {
    PetscReal norm = 0.0, norm0 = 0.0;

    for (PetscInt i = 0; i < k; ++i) norm0 += PetscSqr(A[i * m + j]);
    for (PetscInt l = 0; l < j; ++l) {
      PetscReal dot = 0.0;

      for (PetscInt i = 0; i < k; ++i) dot += A[i * m + l] * A[i * m + j];
      R[l][j] = dot;
      for (PetscInt i = 0; i < k; ++i) A[i * m + j] -= dot * A[i * m + l];
    }
    for (PetscInt i = 0; i < k; ++i) norm += PetscSqr(A[i * m + j]);
    if (!(norm > 1e-16 * norm0) || !(norm0 > 0.0)) return PETSC_FALSE;
    R[j][j] = PetscSqrtReal(norm);
    for (PetscInt i = 0; i < k; ++i) A[i * m + j] /= R[j][j];
  }
  for (PetscInt j = 0; j < m; ++j) {
    qb[j] = 0.0;
    for (PetscInt i = 0; i < k; ++i) qb[j] += A[i * m + j] * b[i];
  }
  for (PetscInt j = m - 1; j >= 0; --j) { /* R c = Q^T b */
    c[j] = qb[j];
    for (PetscInt l = j + 1; l < m; ++l) c[j] -= R[j][l] * c[l];
    c[j] /= R[j][j];
  }
  for (PetscInt i = 0; i < k; ++i) { /* the residual is b less its projection on Q's columns */
    PetscReal r = b[i];

    for (PetscInt j = 0; j < m; ++j) r -= A[i * m + j] * qb[j];
    rss += PetscSqr(r);
  }
  for (PetscInt j = 0; j < m; ++j)
    for (PetscInt l = 0; l < m; ++l) Ri[j][l] = 0.0;
  for (PetscInt j = m - 1; j >= 0; --j) { /* R^{-1}, upper triangular */
    Ri[j][j] = 1.0 / R[j][j];
    for (PetscInt l = j + 1; l < m; ++l) {
      PetscReal sum = 0.0;

      for (PetscInt q = j + 1; q <= l; ++q) sum += R[j][q] * Ri[q][l];
      Ri[j][l] = -sum / R[j][j];
    }
  }
  *s2 = rss / (k - m);
  return PETSC_TRUE;
}

/* The peak and its resolution (the head of the file), on every rank; pressure_max and step, the nodal maximum and its
   step (PostprocessPressureStep()), where there is too little contact to fit. The nodal pressure of the contact's set. */
PetscErrorCode PostprocessPressurePeak(DM dm, Contact contact, PetscReal pressure_max, PetscReal step, PetscReal *peak, PetscReal *resolution)
{
  MPI_Comm          comm = PetscObjectComm((PetscObject)dm);
  const ContactSet *cs;
  PetscInt          dim, nlocal, ntotal, ntops, nnear, n, m, k, lt;
  PetscReal        *mine, *tops, *near, *rows, *A, *b, top[PEAK_STRIDE], t[2][3], rho, c[6], Ri[6][6], s2, pmax, edge;
  PeakNode         *order;

  PetscFunctionBeginUser;
  *peak       = pressure_max;
  *resolution = step;
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(ContactGetSet(contact, &cs));
  /* the largest vertex pressure over all ranks (pressure_max counts every point of the set); the nodes below PEAK_TIE
     of it carry none (a node at the zone's edge whose pressure is a round-off, of either sign, is out on every run and
     partition: the default square's 8 x 8 SNESVI run on 2 ranks gave 0.7124 and 0.7069 in two runs, its count of nodes
     moving across the fit's threshold) */
  pmax = PETSC_MIN_REAL;
  for (PetscInt i = 0; i < cs->n; ++i)
    if (cs->is_vertex[i]) pmax = PetscMax(pmax, cs->pressure[i]);
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &pmax, 1, MPIU_REAL, MPIU_MAX, comm));
  if (!(pmax > 0.0)) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(LocalContactRows(dm, cs, dim, PEAK_TIE * pmax, PETSC_TRUE, &nlocal, &mine));
  PetscCall(MPIU_Allreduce(&nlocal, &ntotal, 1, MPIU_INT, MPI_SUM, comm));
  m = dim == 2 ? 3 : 6;
  k = PetscMin(dim == 2 ? PEAK_NODES_2D : PEAK_NODES_3D, ntotal);
  if (ntotal < 2 * m) {
    PetscCall(PetscFree(mine));
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  /* the top: each rank's first node tied with the largest pressure (TopRow()), the first of those */
  lt = TopRow(nlocal, mine, pmax);
  PetscCall(AllgatherRows(comm, lt >= 0 ? 1 : 0, lt >= 0 ? &mine[lt * PEAK_STRIDE] : mine, &ntops, &tops));
  PetscCall(PetscArraycpy(top, &tops[TopRow(ntops, tops, pmax) * PEAK_STRIDE], PEAK_STRIDE));
  PetscCall(PetscFree(tops));
  /* the patch: the nodes within PEAK_ZONE of the top's distance to the zone's edge (the nearest vertex without pressure,
     PETSC_MAX_REAL where every vertex is in contact), and at least the k nearest; each rank's own such nodes hold all of
     the patch's */
  {
    PetscReal *out;
    PetscInt   nout;

    PetscCall(LocalContactRows(dm, cs, dim, PEAK_TIE * pmax, PETSC_FALSE, &nout, &out));
    edge = PETSC_MAX_REAL;
    for (PetscInt i = 0; i < nout; ++i) edge = PetscMin(edge, RowDistance(&out[i * PEAK_STRIDE], top));
    PetscCall(PetscFree(out));
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &edge, 1, MPIU_REAL, MPIU_MIN, comm));
  edge = edge < PETSC_MAX_REAL ? PEAK_ZONE * edge : 0.0;
  PetscCall(SortByDistance(nlocal, mine, top, &order));
  nnear = PetscMin(k, nlocal);
  while (nnear < nlocal && order[nnear].dist <= edge) ++nnear;
  PetscCall(PetscMalloc1(nnear * PEAK_STRIDE + 1, &near));
  for (PetscInt j = 0; j < nnear; ++j) PetscCall(PetscArraycpy(&near[j * PEAK_STRIDE], &mine[order[j].i * PEAK_STRIDE], PEAK_STRIDE));
  PetscCall(PetscFree(order));
  PetscCall(PetscFree(mine));
  PetscCall(AllgatherRows(comm, nnear, near, &n, &rows));
  PetscCall(PetscFree(near));
  PetscCall(SortByDistance(n, rows, top, &order));
  while (k < n && order[k].dist <= edge) ++k;
  TangentBasis(dim, &top[3], t);
  rho = order[k - 1].dist;
  PetscCall(PetscMalloc2(k * m, &A, k, &b));
  for (PetscInt j = 0; j < k; ++j) {
    Monomials(dim, t, top, rho, &rows[order[j].i * PEAK_STRIDE], &A[j * m]);
    b[j] = rows[order[j].i * PEAK_STRIDE + 6];
  }
  if (LeastSquares(k, m, A, b, c, Ri, &s2)) {
    PetscReal phi[6];

    MonomialsAtMaximum(dim, c, phi);
    *peak = 0.0;
    for (PetscInt l = 0; l < m; ++l) *peak += c[l] * phi[l];
    *resolution = FunctionalDeviation(m, Ri, s2, phi);                               /* the standard error there */
    for (PetscInt j = 1; j < k && order[j].dist <= PEAK_RING * order[1].dist; ++j) { /* the fit's step to the top's neighbours */
      PetscReal d[6], v = 0.0;

      Monomials(dim, t, top, rho, &rows[order[j].i * PEAK_STRIDE], d);
      d[0] = 0.0; /* the step c . (phi_j - phi_top), phi_top = e0 */
      for (PetscInt l = 0; l < m; ++l) v += c[l] * d[l];
      *resolution = PetscMax(*resolution, PetscAbsReal(v) - PEAK_SIGNIFICANT * FunctionalDeviation(m, Ri, s2, d));
    }
  } else
    *resolution = step;
  PetscCall(PetscFree2(A, b));
  PetscCall(PetscFree(order));
  PetscCall(PetscFree(rows));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Checks of the contact set-up and of the resolution of the contact zone: warnings in the summary and in /run, for
   answers that are what was asked but probably not what was meant. A warning never changes the answer.
   - Before the solve, the geometry: the largest initial overlap of Gamma_C's vertices with the obstacle, in cells of
     their faces (an overlap of many cells is a misplaced obstacle more often than a press fit), the part of Gamma_C
     that starts inside the obstacle, and the part where the obstacle's normal (from the body into the obstacle)
     points into the body, against the outward normal of the face: an obstacle facing away from the body, or a plane
     behind it, which the penalty pushes the body through.
   - Before the solve, the material: P1 and Q1 lock as nu -> 1/2, and their nodal tractions oscillate, so that the
     largest pressure is off by a part that refinement does not reduce; from nu = CONTACT_CHECK_LOCKING_NU on it is
     above 1% on make hertz's cylinder (scripts/incompressible.py; docs/hertz.md, "Nearly incompressible bodies"). Such
     a body is warned of, with the cure: quadratic elements; and where the penalty takes eps from E, eps is
     (lambda + 2 mu) / E times softer than the body, which -penalty_eps_modulus pwave restores.
   - After the solve, the resolution: how many cells span the contact zone along Gamma_C (the faces where the contact
     acts at every node: their number in 2D, the diameter in cells of a round zone of that many faces in 3D), warned
     below 4 in 2D and 6 in 3D, where the Gauss rule's force is within about 2% and 3% of a fine mesh's. A zone of a
     few cells is a discretization artefact: the force and the penetration no longer follow eps (docs/running.md,
     "Warnings"; the thresholds are measured by scripts/zone_resolution.py, bench/zone_resolution.md and
     bench/zone_resolution_3d.md). */
#include "contact.h"
#include "mesh.h"
#include "obstacle.h"
#include "physics.h"
#include "app.h"

/* The checks before the solve (the head of the file) of what in describes, into ck. */
PetscErrorCode ContactChecksGeometry(DM dm, const ContactChecksGeometryInputs *in, ContactChecks *ck)
{
  MPI_Comm            comm = PetscObjectComm((PetscObject)dm);
  const MeshBox      *box  = in->box;
  PetscInt            dim, vStart, vEnd;
  PetscReal           sums[3] = {0.0, 0.0, 0.0}, overlap[2] = {0.0, 0.0}; /* area, area facing away, area overlapping; -g/h and -g */
  ContactPressureForm form;

  PetscFunctionBeginUser;
  { /* a mesh file's curved boundary refined by the solver on its chords (-adapt_cycles refuses it: AdaptCheck()) */
    const PetscInt refinements = box->refine + in->grid_refinements;

    if (box->from_file && refinements > 0 && box->curved_ridges >= MESH_CURVED_RIDGES_MIN) {
      ck->curved_refined     = box->curved_ridges;
      ck->curved_refinements = refinements;
      for (PetscInt d = 0; d < 3; ++d) ck->curved_x[d] = box->curved_x[d];
    }
  }
  { /* a nearly incompressible P1/Q1 body (see the head of the file) */
    const Material *mat = in->material;

    if (in->degree == 1 && mat->poisson_ratio >= CONTACT_CHECK_LOCKING_NU) {
      const ContactOptions *copt;

      ck->locking_nu = mat->poisson_ratio;
      PetscCall(ContactGetOptions(in->contact, &copt));
      PetscCall(ContactGetPressureForm(in->contact, &form));
      if (form.law && copt->modulus == PENALTY_MODULUS_YOUNG) /* eps = eps0 h / E, whose E the P-wave modulus outgrows */
        ck->locking_eps_ratio = (mat->lambda + 2.0 * mat->mu) / mat->young_modulus;
    }
  }
  PetscCall(ContactGetPressureForm(in->contact, &form));
  if (!form.acts) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  for (PetscInt s = 0; s < in->scene->bcs.ncontact; ++s) {
    PetscInt *faces, nf;

    PetscCall(MeshGetBoundaryFaces(dm, in->scene->bcs.contact_ids[s], &nf, &faces));
    for (PetscInt i = 0; i < nf; ++i) {
      const PetscInt *support;
      PetscInt       *closure = NULL, ncl;
      PetscReal       n[3] = {0, 0, 0}, xc[3] = {0, 0, 0}, area, nob[3], g, dot = 0.0, diam;

      PetscCall(MeshFaceOutwardGeometry(dm, faces[i], dim, n, xc, &area));
      ObstacleGapNormalAt(&in->scene->obstacle, dim, xc, nob, &g);
      for (PetscInt d = 0; d < dim; ++d) dot += n[d] * nob[d];
      sums[0] += area;
      sums[1] += dot < 0.0 ? area : 0.0; /* a normal along the face (a punch's side beside the body) is not away */
      sums[2] += g < 0.0 ? area : 0.0;
      PetscCall(DMPlexGetSupport(dm, faces[i], &support));
      PetscCall(MeshCellDiameter(dm, support[0], &diam));
      PetscCall(DMPlexGetTransitiveClosure(dm, faces[i], PETSC_TRUE, &ncl, &closure));
      for (PetscInt j = 0; j < ncl; ++j) {
        PetscReal x[3] = {0, 0, 0}, nv[3];

        if (closure[2 * j] < vStart || closure[2 * j] >= vEnd) continue;
        PetscCall(MeshPointPosition(dm, closure[2 * j], x));
        ObstacleGapNormalAt(&in->scene->obstacle, dim, x, nv, &g);
        overlap[0] = PetscMax(overlap[0], -g / diam);
        overlap[1] = PetscMax(overlap[1], -g);
      }
      PetscCall(DMPlexRestoreTransitiveClosure(dm, faces[i], PETSC_TRUE, &ncl, &closure));
    }
    PetscCall(PetscFree(faces));
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, sums, 3, MPIU_REAL, MPIU_SUM, comm));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, overlap, 2, MPIU_REAL, MPIU_MAX, comm));
  ck->overlap_cells    = overlap[0];
  ck->away_fraction    = sums[0] > 0.0 ? sums[1] / sums[0] : 0.0;
  ck->overlap_fraction = sums[0] > 0.0 ? sums[2] / sums[0] : 0.0;
  {
    /* The overlap against the width of the part that overlaps: an indentation prescribed by overlap (a sphere pressed d
       into a body meets it on a disk of radius about sqrt(2 R d), so d is a few percent of that width at the small
       strains of linear elasticity) is no misplaced obstacle, however fine the mesh makes d in cells; an obstacle put
       half the body deep is (0.5 of the width). The width of a half or quarter of a round part, as a symmetric model
       meshes it, is half the whole's: the ratio errs toward a warning. */
    const PetscReal width = dim == 2 ? sums[2] : 2.0 * PetscSqrtReal(sums[2] / PETSC_PI);

    ck->overlap_ratio = width > 0.0 ? overlap[1] / width : 0.0;
  }
  /* A cone of half-angle alpha pressed d into a flat body overlaps it on a width 2 d tan(alpha), a ratio 1/(2 tan(alpha)):
     0.18 for Berkovich's equivalent cone (70.3 degrees), above CONTACT_CHECK_OVERLAP_RATIO at any depth. Its limit is
     that ratio times CONTACT_CHECK_OVERLAP_CONE, which a quarter model's halved width (a doubled ratio) stays below. */
  ck->overlap_ratio_limit = CONTACT_CHECK_OVERLAP_RATIO;
  if (in->scene->obstacle.type == OBSTACLE_CONE)
    ck->overlap_ratio_limit =
        PetscMax(CONTACT_CHECK_OVERLAP_RATIO, CONTACT_CHECK_OVERLAP_CONE / (2.0 * PetscTanReal(in->scene->obstacle.half_angle * PETSC_PI / 180.0)));
  ck->geometry_checked = PETSC_TRUE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The eigenvalues of a symmetric 3 x 3 matrix, largest first, in closed form (the trigonometric solution of its
   characteristic cubic, Smith, CACM 4, 1961). */
static void SymmetricEigenvalues(const PetscReal C[3][3], PetscReal e[3])
{
  const PetscReal p1 = C[0][1] * C[0][1] + C[0][2] * C[0][2] + C[1][2] * C[1][2], q = (C[0][0] + C[1][1] + C[2][2]) / 3.0;
  const PetscReal p2 = PetscSqr(C[0][0] - q) + PetscSqr(C[1][1] - q) + PetscSqr(C[2][2] - q) + 2.0 * p1, p = PetscSqrtReal(p2 / 6.0);
  PetscReal       B[3][3], r, phi, e1, e3;

  if (p == 0.0) { /* a multiple of the identity */
    e[0] = e[1] = e[2] = q;
    return;
  }
  for (PetscInt a = 0; a < 3; ++a)
    for (PetscInt b = 0; b < 3; ++b) B[a][b] = (C[a][b] - (a == b ? q : 0.0)) / p;
  r    = 0.5 * (B[0][0] * (B[1][1] * B[2][2] - B[1][2] * B[2][1]) - B[0][1] * (B[1][0] * B[2][2] - B[1][2] * B[2][0]) +
             B[0][2] * (B[1][0] * B[2][1] - B[1][1] * B[2][0]));
  phi  = r <= -1.0 ? PETSC_PI / 3.0 : r >= 1.0 ? 0.0 : PetscAcosReal(r) / 3.0;
  e1   = q + 2.0 * p * PetscCosReal(phi);                        /* the largest */
  e3   = q + 2.0 * p * PetscCosReal(phi + 2.0 * PETSC_PI / 3.0); /* the smallest */
  e[0] = e1;
  e[1] = 3.0 * q - e1 - e3;
  e[2] = e3;
}

static int ComparePoints(const void *a, const void *b)
{
  const PetscInt x = *(const PetscInt *)a, y = *(const PetscInt *)b;
  return x < y ? -1 : x > y;
}

/* After PostprocessContact(): the faces of Gamma_C whose every node carries contact force (a positive pressure). A face
   with only some nodes pressed is the zone's edge, which the rule smears over a cell or two whatever the zone's true
   width: counting it, a zone narrower than a cell counted 4 faces at every h (bench/zone_resolution.md).
   SNESVI's pressure is the reaction at every node, round-off (1e-16 of the largest) at the free ones: a node carries
   force there above ContactActivityFloor(), the tolerance of its active set. Without it the count changed
   with the round-off, 4 or 6 faces between two identical runs of the square on 2 ranks.
   Of the solution u with the contact on Gamma_C of bcs, force_vector the obstacle's force on the body (RunStats'
   contact_force_vector); into ck. */
PetscErrorCode ContactChecksResolution(DM dm, Contact contact, const BoundarySet *bcs, const PetscReal force_vector[3], Vec u, ContactChecks *ck)
{
  MPI_Comm            comm = PetscObjectComm((PetscObject)dm);
  const ContactSet   *cs;
  PetscInt            dim, nzone = 0, pressed = 0, (*pairs)[2];
  PetscReal           floor = 0.0, moments[10] = {0}; /* area, its first moments, its second moments xx, xy, xz, yy, yz, zz */
  ContactPressureForm form;

  PetscFunctionBeginUser;
  PetscCall(ContactGetPressureForm(contact, &form));
  if (!form.acts) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(ContactGetSet(contact, &cs));
  PetscCall(ContactActivityFloor(contact, &floor));
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(PetscMalloc1(cs->n + 1, &pairs)); /* (point, node) sorted by point: a face's nodes found by bisection */
  for (PetscInt i = 0; i < cs->n; ++i) {
    pairs[i][0] = cs->point[i];
    pairs[i][1] = i;
  }
  qsort(pairs, (size_t)cs->n, sizeof(pairs[0]), ComparePoints);
  for (PetscInt s = 0; s < bcs->ncontact; ++s) {
    PetscInt *faces, nf;

    PetscCall(MeshGetBoundaryFaces(dm, bcs->contact_ids[s], &nf, &faces));
    for (PetscInt i = 0; i < nf; ++i) {
      PetscInt *closure = NULL, ncl, nodes = 0, acting = 0;

      PetscCall(DMPlexGetTransitiveClosure(dm, faces[i], PETSC_TRUE, &ncl, &closure));
      for (PetscInt j = 0; j < ncl; ++j) {
        PetscInt lo = 0, hi = cs->n - 1;

        while (lo <= hi) {
          const PetscInt mid = (lo + hi) / 2;

          if (pairs[mid][0] == closure[2 * j]) {
            ++nodes;
            acting += cs->pressure[pairs[mid][1]] > floor;
            break;
          }
          if (pairs[mid][0] < closure[2 * j])
            lo = mid + 1;
          else
            hi = mid - 1;
        }
      }
      PetscCall(DMPlexRestoreTransitiveClosure(dm, faces[i], PETSC_TRUE, &ncl, &closure));
      nzone += nodes > 0 && acting == nodes;
      pressed += acting;
      if (dim == 3 && nodes > 0 && acting == nodes) { /* the zone's second moments, for its width (below) */
        PetscReal n[3], xc[3], area;

        PetscCall(MeshFaceOutwardGeometry(dm, faces[i], dim, n, xc, &area));
        moments[0] += area;
        for (PetscInt a = 0, k = 4; a < 3; ++a) {
          moments[1 + a] += area * xc[a];
          for (PetscInt b = a; b < 3; ++b, ++k) moments[k] += area * xc[a] * xc[b];
        }
      }
    }
    PetscCall(PetscFree(faces));
  }
  PetscCall(PetscFree(pairs));
  PetscCall(MPIU_Allreduce(&nzone, &ck->zone_faces, 1, MPIU_INT, MPI_SUM, comm));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &pressed, 1, MPIU_INT, MPI_SUM, comm));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, moments, 10, MPIU_REAL, MPIU_SUM, comm));
  ck->zone_pressed = (PetscBool)(pressed > 0);
  /* in 3D, the diameter in cells of a round zone of that many faces: n faces of area s^2/2 (s the face's size, the leg of
     a right triangle) cover pi D^2 / 4 = n s^2 / 2, so D / s = sqrt(2 n / pi). A zone that is no disk (a rigid
     cylinder's line contact on a block: a strip two cells wide, which the round zone's count took for 8 cells across)
     is as many cells across as its narrowest width where it is a strip, CONTACT_CHECK_STRIP_ASPECT times longer than
     wide: its width and length 4 sqrt(lambda), lambda the middle and the largest eigenvalue of the faces' second moments
     about their centroid (the smallest is across a flat or gently curved zone's thickness; a disk's 4 sqrt(r^2/4) is
     its diameter, a strip's 4 sqrt(w^2/12) 1.15 times its width w). A rounder zone keeps the round count, the measure
     the thresholds were set with: a quarter of a round zone, as a symmetric model meshes it, is 1.4 times longer than
     wide, and on a few faces the second moments' width falls short of the round count. */
  ck->zone_cells = dim == 2 ? (PetscReal)ck->zone_faces : PetscSqrtReal(2.0 * (PetscReal)ck->zone_faces / PETSC_PI);
  if (dim == 3 && ck->zone_faces > 0 && moments[0] > 0.0) {
    const PetscReal A = moments[0], s = PetscSqrtReal(2.0 * A / (PetscReal)ck->zone_faces);
    PetscReal       c[3], C[3][3], e[3], width, length;

    for (PetscInt a = 0; a < 3; ++a) c[a] = moments[1 + a] / A;
    for (PetscInt a = 0, k = 4; a < 3; ++a)
      for (PetscInt b = a; b < 3; ++b, ++k) C[a][b] = C[b][a] = moments[k] / A - c[a] * c[b];
    SymmetricEigenvalues(C, e);
    width                = 4.0 * PetscSqrtReal(PetscMax(e[1], 0.0));
    length               = 4.0 * PetscSqrtReal(PetscMax(e[0], 0.0));
    ck->zone_width_cells = width / s;
    ck->zone_strip       = (PetscBool)(ck->zone_faces >= 6 && length >= CONTACT_CHECK_STRIP_ASPECT * width); /* 6: a strip a cell wide, 3 long */
    if (ck->zone_strip) ck->zone_cells = ck->zone_width_cells;
  }
  /* a strip (a line contact) is a 2D contact in its cross-section: the 2D threshold on its width */
  ck->zone_limit         = dim == 2 || ck->zone_strip ? CONTACT_CHECK_ZONE_CELLS_2D : CONTACT_CHECK_ZONE_CELLS_3D;
  ck->resolution_checked = PETSC_TRUE;
  PetscCall(ContactUnseenNodes(contact, u, NULL, &ck->unseen_nodes, &ck->unseen_force));
  {
    const PetscReal *f     = force_vector;
    const PetscReal  force = PetscSqrtReal(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);

    ck->unseen_share = ck->unseen_nodes == 0 ? 0.0 : (force > 0.0 ? ck->unseen_force / force : PETSC_INFINITY);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The warnings of the checks, one sentence each, through print (the summary) or counted. */
PetscErrorCode ContactChecksWarnings(MPI_Comm comm, const ContactChecks *ck, PetscBool print, PetscInt *nwarnings)
{
  PetscInt n = 0;

  PetscFunctionBeginUser;
  if (ck->geometry_checked && ck->overlap_cells > CONTACT_CHECK_OVERLAP_CELLS && ck->overlap_ratio > ck->overlap_ratio_limit) {
    ++n;
    if (print)
      PetscCall(PetscPrintf(comm,
                            "  WARNING: Gamma_C starts %.3g cells deep inside the obstacle (on %.0f%% of its area, %.2g times the width of that "
                            "part): a misplaced obstacle? (check -obstacle_point, -obstacle_center, -obstacle_translate)\n",
                            (double)ck->overlap_cells, (double)(100.0 * ck->overlap_fraction), (double)ck->overlap_ratio));
  }
  if (ck->geometry_checked && ck->away_fraction > 0.5) {
    ++n;
    if (print)
      PetscCall(PetscPrintf(comm,
                            "  WARNING: on %.0f%% of Gamma_C the obstacle's normal points into the body: the obstacle faces away from it or lies "
                            "behind it (-obstacle_normal is the normal from the body into the obstacle)\n",
                            (double)(100.0 * ck->away_fraction)));
  }
  if (ck->resolution_checked && ck->zone_pressed && ck->zone_cells < ck->zone_limit) { /* zone_faces 0: a node or an edge alone presses */
    ++n;
    if (print)
      PetscCall(PetscPrintf(comm,
                            "  WARNING: the contact zone spans %.1f cell(s) along Gamma_C (%" PetscInt_FMT
                            " faces), fewer than %.0f: the force and the penetration are a discretization artefact there; refine near the "
                            "contact\n",
                            (double)ck->zone_cells, ck->zone_faces, (double)ck->zone_limit));
  }
  if (ck->resolution_checked && ck->unseen_nodes > 0 && !(ck->unseen_share <= CONTACT_CHECK_UNSEEN_SHARE)) {
    char share[64];

    if (ck->unseen_share >= PETSC_INFINITY)
      PetscCall(PetscSNPrintf(share, sizeof(share), "the rule exerts no force at all"));
    else
      PetscCall(PetscSNPrintf(share, sizeof(share), "the penalty law would put %.2g%% of the force on them", (double)(100.0 * ck->unseen_share)));
    ++n;
    if (print)
      PetscCall(PetscPrintf(comm,
                            "  WARNING: %" PetscInt_FMT " node(s) of Gamma_C penetrate the obstacle while the penalty rule exerts no force on them "
                            "(%s): the contact zone there is smaller than the faces, and the rule's points miss it (the force and the estimate "
                            "see no contact); refine near the contact, or let -adapt_cycles or -accuracy refine there\n",
                            ck->unseen_nodes, share));
  }
  if (ck->curved_refined) {
    ++n;
    if (print)
      PetscCall(PetscPrintf(comm,
                            "  WARNING: the mesh file's boundary turns by less than 20 degrees at %" PetscInt_FMT
                            " of its vertices or edges (one near (%g, %g, %g)): a curved boundary's chords, which the solver's %" PetscInt_FMT
                            " refinement(s) (-dm_refine, -contact_grid_sequence) split on the chords, so that the answer is the file's polygon's, "
                            "not the curved body's (the Hertz cylinder meshed at h = 0.05 and refined 3 times: its contact width 25%% short); "
                            "mesh finer with Gmsh instead\n",
                            ck->curved_refined, (double)ck->curved_x[0], (double)ck->curved_x[1], (double)ck->curved_x[2], ck->curved_refinements));
  }
  if (ck->locking_nu > 0.0) {
    char eps[256] = "";

    if (ck->locking_eps_ratio > 0.0)
      PetscCall(PetscSNPrintf(eps, sizeof(eps),
                              "; the penalty's eps = h/E is %.3g times softer than the body's lambda + 2 mu, which -penalty_eps_modulus pwave "
                              "restores",
                              (double)ck->locking_eps_ratio));
    ++n;
    if (print)
      PetscCall(
          PetscPrintf(comm,
                      "  WARNING: nu = %g: linear elements lock as nu -> 1/2, and the contact pressure with them (the Hertz cylinder's "
                      "largest pressure 1%% off at nu = 0.45, 2%% to 5%% at 0.49, 19%% at 0.499, not falling as the mesh is refined); "
                      "quadratic elements (-displacement_petscspace_degree 2) keep its half-width within 1%% up to nu = 0.499, where linear ones "
                      "are 12.8%% short%s\n",
                      (double)ck->locking_nu, eps));
  }
  if (nwarnings) *nwarnings = n;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The checks in /run: the number of warnings, and the values checked (ContactChecksGeometry(), ContactChecksResolution();
   nothing of a check not made, as without contact): the initial overlap, an obstacle facing away, a curved boundary
   the solver refined, the contact zone's cells (and a strip's width), the contact the mesh does not see. */
PetscErrorCode ContactChecksWrite(MPI_Comm comm, const ContactChecks *ck, PetscViewer v)
{
  PetscInt nwarn;

  PetscFunctionBeginUser;
  PetscCall(ContactChecksWarnings(comm, ck, PETSC_FALSE, &nwarn));
  PetscCall(RunAttrInt(v, nwarn, "warnings"));
  if (ck->geometry_checked) {
    PetscCall(RunAttrReal(v, ck->overlap_cells, "initial_overlap_cells"));
    PetscCall(RunAttrReal(v, ck->overlap_fraction, "initial_overlap_fraction"));
    PetscCall(RunAttrReal(v, ck->overlap_ratio, "initial_overlap_ratio"));
    PetscCall(RunAttrReal(v, ck->away_fraction, "obstacle_away_fraction"));
  }
  PetscCall(RunAttrInt(v, ck->curved_refined ? 1 : 0, "curved_boundary_refined")); /* a mesh file's curved boundary refined on its chords */
  if (ck->resolution_checked) {
    PetscCall(RunAttrInt(v, ck->zone_faces, "contact_zone_faces"));
    PetscCall(RunAttrReal(v, ck->zone_cells, "contact_zone_cells"));
    if (ck->zone_strip) PetscCall(RunAttrReal(v, ck->zone_width_cells, "contact_zone_width_cells")); /* a line contact's */
    PetscCall(RunAttrInt(v, ck->unseen_nodes, "contact_unseen_nodes"));                              /* penetrating with no force from the rule, */
    PetscCall(RunAttrReal(v, ck->unseen_force, "contact_unseen_force")); /* the law's force there: a warning above a share */
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Remeshing a Gmsh model with a size field (-adapt_model, src/solver/adapt.c): the adaptive cycles' refinement where
   the mesh's own cannot serve. PETSc 3.18 as Debian builds it refines triangles locally (skeleton-based refinement,
   mesh_refine.c) but not tetrahedra, and any refinement of a mesh file splits its curved boundary's edges on their
   chords, so that the body it solves stays the first mesh's polygon. Gmsh meshes the model itself, its curved
   boundary exact, with a size given at every point: here the size each cell of the current mesh asks for, as a
   list-based view on the cells, used as the background mesh (Gmsh's "PostView" field). The model's physical groups,
   which the run's boundary conditions name, are those of the new mesh.
   The view's values (measured on the Hertz cylinder and sphere from uniform meshes at h = 0.1 and 0.2):
   - 2D: each cell's own size, constant on it: the marked cells' halves, exactly where marked. The cylinder reached
     -accuracy 0.03 in 9 cycles, 9,013 unknowns and 1.7 s. With the smallest size of a vertex's cells at each vertex
     (continuous) it took 10 cycles, 115,018 unknowns and 21 s; with their mean, 14 cycles, 16,509 unknowns and 3.3 s.
   - 3D: the smallest size of the vertex's cells at each vertex. With the cells' own sizes the sphere's first cycles
     (one or two cells marked around a contact the mesh does not see) did not refine at all (314 to 460 unknowns in 6
     cycles, the estimate growing), and once Gmsh met overlapping facets on the curved surface; with the mean the mesh
     shrank. The smallest spreads a mark to the cells around it: 314 to 55,255 unknowns in 7 cycles.
   - 2D without Gmsh's Laplace smoothing (Mesh.Smoothing 0): the smoothing was a quarter of the cylinder's -accuracy
     0.03 run (perf), which took 1.22 s and 8,556 unknowns without it against 1.65 s and 12,615 with it (the stop moves
     with the meshes; every bar still covered over 15 cycles), and 0.01 the same time (3.5 to 3.8 s, 39,270 unknowns
     against 35,679). In 3D it is kept: without it the sphere's -accuracy 0.1 took 77,923 unknowns and 17.8 s against
     58,233 and 12.2 s.
   - 2D with Gmsh's Delaunay algorithm (Mesh.Algorithm 5) rather than its default frontal-Delaunay (6), whose point
     insertion with the background mesh's size lookups was a third of the cylinder's 0.01 run: 3 alternated pairs,
     0.03 in 1.18 s against 1.31 s (7,056 unknowns against 8,556), 0.01 in 2.91 s against 3.81 s (36,047 against
     39,270); every bar still covered over 15 cycles. In 3D (the surface meshes) the default is kept: the sphere took
     10.7 and 13.3 s against 14.2 and 14.0 s, but the sphere indenter 9.1 and 8.7 s against 7.7 and 8.1 s.
   Gmsh runs on rank 0 on the gathered cells, sorted by their centroids so that the view is the same on any number of
   ranks (Gmsh's search of a point's cell depends on their order where the values jump); the mesh it makes is taken
   from its API on rank 0, built as PETSc's reader builds the file Gmsh would write (mesh_gmsh_build.c), and
   distributed as a mesh file is (METIS).
   Without a model, the box of the options (-dm_plex_box_*) is the model: a 3D box adapts so. */
#include <dlfcn.h>
#include <gmshc.h>
#include <petscsf.h>
#include <stdlib.h>
#include <unistd.h>
#include "mesh.h"

/* Gmsh's C API, loaded at the first remesh (GmshLoad()): linked, its library and OpenCASCADE's added 0.22 s to the
   start of every run (0.44 s to 0.66 s on a 4 x 4 box), remeshing or not. */
#define GMSH_FUNCTIONS(X)                  \
  X(gmshFinalize)                          \
  X(gmshFree)                              \
  X(gmshInitialize)                        \
  X(gmshLoggerGetLastError)                \
  X(gmshModelAdd)                          \
  X(gmshModelAddPhysicalGroup)             \
  X(gmshModelGetBoundingBox)               \
  X(gmshModelGetEntities)                  \
  X(gmshModelGetPhysicalGroups)            \
  X(gmshModelGetPhysicalGroupsForEntity)   \
  X(gmshModelGetPhysicalName)              \
  X(gmshModelMeshGetElements)              \
  X(gmshModelMeshGetNodes)                 \
  X(gmshModelMeshFieldAdd)                 \
  X(gmshModelMeshFieldSetAsBackgroundMesh) \
  X(gmshModelMeshFieldSetNumber)           \
  X(gmshModelMeshGenerate)                 \
  X(gmshModelOccAddBox)                    \
  X(gmshModelOccSynchronize)               \
  X(gmshOpen)                              \
  X(gmshOptionGetNumber)                   \
  X(gmshOptionSetNumber)                   \
  X(gmshViewAdd)                           \
  X(gmshViewAddListData)                   \
  X(gmshWrite)
#define GMSH_DECLARE(f) __typeof__(f) *f;
static struct {
  void *lib;
  GMSH_FUNCTIONS(GMSH_DECLARE)
} G;

/* RTLD_DEEPBIND: Gmsh's libraries look their symbols up in their own dependencies first, not through the solver's
   whole global scope (PETSc's, MPI's and HDF5's libraries) before them. Gmsh brings 71 libraries of its own
   (OpenCASCADE, FLTK, image formats); its loading took 0.24 to 0.35 s of the Hertz cylinder's first remesh so, 0.08 to
   0.11 s with it (RTLD_LAZY alone: 0.24 to 0.27 s). It also keeps Gmsh's libraries from binding to a same-named symbol
   of the solver's. Not under AddressSanitizer, whose runtime refuses it. */
#if defined(RTLD_DEEPBIND) && !defined(__SANITIZE_ADDRESS__)
#  define GMSH_DLOPEN (RTLD_NOW | RTLD_LOCAL | RTLD_DEEPBIND)
#else
#  define GMSH_DLOPEN (RTLD_NOW | RTLD_LOCAL)
#endif

static PetscErrorCode GmshLoad(void)
{
  PetscFunctionBeginUser;
  if (G.lib) PetscFunctionReturn(PETSC_SUCCESS);
  G.lib = dlopen("libgmsh.so.4.8", GMSH_DLOPEN);
  if (!G.lib) G.lib = dlopen("libgmsh.so", GMSH_DLOPEN);
  PetscCheck(G.lib, PETSC_COMM_SELF, PETSC_ERR_LIB, "Gmsh's library cannot be loaded (%s): apt-get install libgmsh4.8", dlerror());
#define GMSH_LOAD(f)                       \
  G.f = (__typeof__(f) *)dlsym(G.lib, #f); \
  PetscCheck(G.f, PETSC_COMM_SELF, PETSC_ERR_LIB, "Gmsh's library has no %s", #f);
  GMSH_FUNCTIONS(GMSH_LOAD)
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* A Gmsh call's error as a PETSc error, with Gmsh's last message. */
#define GmshCall(call, what)                                                                                       \
  do {                                                                                                             \
    int ierr_gmsh = 0;                                                                                             \
    call;                                                                                                          \
    if (ierr_gmsh) {                                                                                               \
      char *msg = NULL;                                                                                            \
      int   e2  = 0;                                                                                               \
      G.gmshLoggerGetLastError(&msg, &e2);                                                                         \
      SETERRQ(PETSC_COMM_SELF, PETSC_ERR_LIB, "Gmsh failed to %s: %s", what, msg &&msg[0] ? msg : "(no message)"); \
    }                                                                                                              \
  } while (0)

/* The 3D box of the options as a Gmsh model (a 2D box is refined by PETSc, AdaptSolve()): an OpenCASCADE box, its
   sides' physical groups numbered as PETSc numbers them (MeshBoxFaceId(), found by their bounding boxes), the body 10. */
static PetscErrorCode GmshBoxModel(const MeshBox *box)
{
  const PetscInt dim = box->dim;
  const double  *lo = box->lower, *hi = box->upper;
  int           *dimtags = NULL, body;
  size_t         n       = 0;

  PetscFunctionBeginUser;
  GmshCall(G.gmshModelAdd("box", &ierr_gmsh), "add the box model");
  PetscCheck(dim == 3, PETSC_COMM_SELF, PETSC_ERR_PLIB, "the box's Gmsh model is 3D");
  GmshCall(body = G.gmshModelOccAddBox(lo[0], lo[1], lo[2], hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], -1, &ierr_gmsh), "add the box");
  GmshCall(G.gmshModelOccSynchronize(&ierr_gmsh), "synchronize the box");
  GmshCall(G.gmshModelGetEntities(&dimtags, &n, (int)dim - 1, &ierr_gmsh), "list the box's sides");
  for (size_t i = 0; i < n / 2; ++i) {
    double   bb[6];
    int      side = dimtags[2 * i + 1];
    PetscInt id   = -1;

    GmshCall(G.gmshModelGetBoundingBox((int)dim - 1, side, &bb[0], &bb[1], &bb[2], &bb[3], &bb[4], &bb[5], &ierr_gmsh), "bound a side");
    for (PetscInt d = 0; d < dim; ++d) {
      const double tol = 1e-6 * (hi[d] - lo[d]) + 1e-6; /* OpenCASCADE pads its bounding boxes by about 1e-7 */

      if (bb[3 + d] - bb[d] > 2 * tol) continue; /* the side is flat across d */
      id = MeshBoxFaceId(dim, d, PetscAbsReal(bb[d] - lo[d]) < PetscAbsReal(bb[d] - hi[d]) ? 0 : 1);
    }
    PetscCheck(id > 0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "a side of the Gmsh box is on no side of the box");
    GmshCall(G.gmshModelAddPhysicalGroup((int)dim - 1, &side, 1, (int)id, &ierr_gmsh), "name a side");
  }
  G.gmshFree(dimtags);
  GmshCall(G.gmshModelAddPhysicalGroup((int)dim, &body, 1, 10, &ierr_gmsh), "name the body");
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The nodes of a Gmsh element type: points, and first-order lines, triangles and tetrahedra (-1: another type). */
static PetscInt GmshTypeNodes(int type)
{
  switch (type) {
    case 15:
      return 1;
    case 1:
      return 2;
    case 2:
      return 3;
    case 4:
      return 4;
    default:
      return -1;
  }
}

/* n more entries of m PetscInts each in *a, of capacity *cap entries (doubled as needed), after *len of them. */
static PetscErrorCode GrowInts(PetscInt **a, PetscInt *cap, PetscInt len, PetscInt n, PetscInt m)
{
  PetscInt *grown;

  PetscFunctionBeginUser;
  if (len + n <= *cap) PetscFunctionReturn(PETSC_SUCCESS);
  *cap = PetscMax(2 * *cap, len + n);
  PetscCall(PetscMalloc1(*cap * m, &grown));
  PetscCall(PetscArraycpy(grown, *a, len * m));
  PetscCall(PetscFree(*a));
  *a = grown;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The mesh Gmsh made (rank 0), numbered as PETSc's Gmsh reader numbers the file Gmsh would write (mesh_gmsh_build.c):
   the elements that file saves (where the model has physical groups, those of their entities, unless the model sets
   Mesh.SaveAll), in its order (the entities of dimension 0 to dim, each by tag), the nodes they use in Gmsh's node
   order (the same entities'), the cells oriented as DMPlexReorderCell() orients them, and the physical groups' names. */
static PetscErrorCode GmshTakeMesh(PetscInt dim, MeshSimplices *s)
{
  size_t    *node_tags = NULL, nnodes = 0, ncoord = 0, npar = 0, ngroups = 0;
  double    *xyz = NULL, *par = NULL, save_all = 0.0;
  int       *groups = NULL;
  PetscInt  *index, *vertex, tag_max = 0, ccap = 0, fcap = 0, ccap_set = 0, fcap_set = 0;
  PetscBool *used;

  PetscFunctionBeginUser;
  PetscCall(PetscMemzero(s, sizeof(*s)));
  s->dim = dim;
  GmshCall(G.gmshModelMeshGetNodes(&node_tags, &nnodes, &xyz, &ncoord, &par, &npar, -1, -1, 0, 0, &ierr_gmsh), "get the mesh's nodes");
  for (size_t i = 0; i < nnodes; ++i) tag_max = PetscMax(tag_max, (PetscInt)node_tags[i]);
  PetscCall(PetscMalloc1(tag_max + 1, &index));
  for (PetscInt t = 0; t <= tag_max; ++t) index[t] = -1;
  for (size_t i = 0; i < nnodes; ++i) index[node_tags[i]] = (PetscInt)i;
  PetscCall(PetscCalloc2(nnodes + 1, &used, nnodes + 1, &vertex));
  GmshCall(G.gmshModelGetPhysicalGroups(&groups, &ngroups, -1, &ierr_gmsh), "list the physical groups");
  for (size_t g = 0; g < ngroups / 2; ++g) { /* the names, as the file's $PhysicalNames; dim, tag pairs */
    char *name = NULL;

    GmshCall(G.gmshModelGetPhysicalName(groups[2 * g], groups[2 * g + 1], &name, &ierr_gmsh), "name a physical group");
    if (name && name[0] && strlen(name) < sizeof(s->names[0].name) && s->nnames < MESH_MAX_NAMES) {
      s->names[s->nnames].dim = groups[2 * g];
      s->names[s->nnames].tag = groups[2 * g + 1];
      PetscCall(PetscStrncpy(s->names[s->nnames].name, name, sizeof(s->names[0].name)));
      s->nnames++;
    }
    G.gmshFree(name);
  }
  G.gmshFree(groups);
  GmshCall(G.gmshOptionGetNumber("Mesh.SaveAll", &save_all, &ierr_gmsh), "get Mesh.SaveAll");
  for (int d = 0; d <= (int)dim; ++d) {
    int   *dimtags = NULL;
    size_t nent    = 0;

    GmshCall(G.gmshModelGetEntities(&dimtags, &nent, d, &ierr_gmsh), "list the model's entities");
    for (size_t e = 0; e < nent / 2; ++e) { /* dim, tag pairs */
      int     *phys = NULL, *types = NULL;
      size_t   nphys = 0, ntypes = 0, *etags_n = NULL, netags = 0, *enodes_n = NULL, nenodes = 0, **etags = NULL, **enodes = NULL;
      PetscInt first;

      GmshCall(G.gmshModelGetPhysicalGroupsForEntity(d, dimtags[2 * e + 1], &phys, &nphys, &ierr_gmsh), "list an entity's physical groups");
      first = nphys ? (PetscInt)phys[0] : -1;
      G.gmshFree(phys);
      if (ngroups && !nphys && save_all == 0.0) continue; /* not saved */
      GmshCall(
          G.gmshModelMeshGetElements(&types, &ntypes, &etags, &etags_n, &netags, &enodes, &enodes_n, &nenodes, d, dimtags[2 * e + 1], &ierr_gmsh),
          "get an entity's elements");
      for (size_t t = 0; t < ntypes; ++t) {
        const PetscInt  nn = GmshTypeNodes(types[t]), count = nn > 0 ? (PetscInt)(enodes_n[t] / (size_t)nn) : 0;
        const PetscBool cell = (PetscBool)(d == (int)dim), face = (PetscBool)(d == (int)dim - 1);

        PetscCheck(nn > 0, PETSC_COMM_SELF, PETSC_ERR_SUP, "Gmsh made elements of type %d (first-order simplices only)", types[t]);
        if (cell) {
          PetscCall(GrowInts(&s->cells, &ccap, s->ncells, count, nn));
          PetscCall(GrowInts(&s->cell_set, &ccap_set, s->ncells, count, 1));
        }
        if (face) {
          PetscCall(GrowInts(&s->faces, &fcap, s->nfaces, count, nn));
          PetscCall(GrowInts(&s->face_set, &fcap_set, s->nfaces, count, 1));
        }
        for (PetscInt i = 0; i < count; ++i) {
          for (PetscInt k = 0; k < nn; ++k) {
            const size_t   tag = enodes[t][i * nn + k];
            const PetscInt at  = tag <= (size_t)tag_max ? index[tag] : -1;

            PetscCheck(at >= 0, PETSC_COMM_SELF, PETSC_ERR_LIB, "Gmsh's element names node %zu, which its nodes do not have", tag);
            used[at] = PETSC_TRUE;
            if (cell) s->cells[(s->ncells + i) * nn + k] = at;
            if (face) s->faces[(s->nfaces + i) * nn + k] = at;
          }
          if (cell) s->cell_set[s->ncells + i] = first;
          if (face) s->face_set[s->nfaces + i] = first;
        }
        if (cell) s->ncells += count;
        if (face) s->nfaces += count;
        G.gmshFree(etags[t]);
        G.gmshFree(enodes[t]);
      }
      G.gmshFree(types);
      G.gmshFree(etags);
      G.gmshFree(etags_n);
      G.gmshFree(enodes);
      G.gmshFree(enodes_n);
    }
    G.gmshFree(dimtags);
  }
  for (size_t i = 0; i < nnodes; ++i) vertex[i] = used[i] ? s->nverts++ : -1; /* PETSc's vertexMap */
  /* the coordinates as the file Gmsh writes holds them, to 16 significant digits: Gmsh's own doubles differ by an ulp,
     and through the remeshing's sensitivity (the sizes, the marking's order, Gmsh's insertions) an ulp moves the later
     cycles' meshes (the cylinder's 1% run from its ninth cycle on), so that -mesh_remeshed_petsc_read would no longer
     give the same run */
  PetscCall(PetscMalloc1(s->nverts * dim + 1, &s->coords));
  for (size_t i = 0; i < nnodes; ++i)
    if (vertex[i] >= 0)
      for (PetscInt j = 0; j < dim; ++j) {
        char digits[32];

        (void)snprintf(digits, sizeof(digits), "%.16g", xyz[3 * i + j]);
        s->coords[vertex[i] * dim + j] = (PetscReal)strtod(digits, NULL);
      }
  for (PetscInt c = 0; c < s->ncells; ++c) {
    for (PetscInt k = 0; k <= dim; ++k) s->cells[c * (dim + 1) + k] = vertex[s->cells[c * (dim + 1) + k]];
    PetscCall(DMPlexInvertCell(dim == 2 ? DM_POLYTOPE_TRIANGLE : DM_POLYTOPE_TETRAHEDRON, &s->cells[c * (dim + 1)]));
  }
  for (PetscInt f = 0; f < s->nfaces * dim; ++f) s->faces[f] = vertex[s->faces[f]];
  G.gmshFree(node_tags);
  G.gmshFree(xyz);
  G.gmshFree(par);
  PetscCall(PetscFree(index));
  PetscCall(PetscFree2(used, vertex));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Rank 0's part: the model opened (or the box built), the cells' sizes as its background mesh, the mesh generated, and
   taken from Gmsh's API (made) or, with out, written to that file. data: ncells cells of nv vertices, each as Gmsh's
   list data (x of the vertices, then y, then z, then the size at each). */
static PetscErrorCode GmshRemesh(const char model[], const MeshBox *box, PetscInt dim, PetscInt ncells, PetscInt nv, double data[], const char out[],
                                 MeshSimplices *made)
{
  int view, field;

  PetscFunctionBeginUser;
  PetscCall(GmshLoad());
  GmshCall(G.gmshInitialize(0, NULL, 0, &ierr_gmsh), "start");
  GmshCall(G.gmshOptionSetNumber("General.Terminal", 0, &ierr_gmsh), "set General.Terminal");
  GmshCall(G.gmshOptionSetNumber("General.NumThreads", 1, &ierr_gmsh), "set General.NumThreads");
  if (model[0])
    GmshCall(G.gmshOpen(model, &ierr_gmsh), "open the model (-adapt_model)");
  else
    PetscCall(GmshBoxModel(box));
  /* the size is the background mesh's alone: not the model's points', not extended from the boundary, not the
     curvature's */
  GmshCall(G.gmshOptionSetNumber("Mesh.MeshSizeExtendFromBoundary", 0, &ierr_gmsh), "set Mesh.MeshSizeExtendFromBoundary");
  GmshCall(G.gmshOptionSetNumber("Mesh.MeshSizeFromPoints", 0, &ierr_gmsh), "set Mesh.MeshSizeFromPoints");
  GmshCall(G.gmshOptionSetNumber("Mesh.MeshSizeFromCurvature", 0, &ierr_gmsh), "set Mesh.MeshSizeFromCurvature");
  GmshCall(G.gmshOptionSetNumber("Mesh.MshFileVersion", 4.1, &ierr_gmsh), "set Mesh.MshFileVersion");
  /* 2D: Gmsh's Delaunay algorithm, no Laplace smoothing (see the head of the file) */
  if (dim == 2) {
    GmshCall(G.gmshOptionSetNumber("Mesh.Algorithm", 5, &ierr_gmsh), "set Mesh.Algorithm");
    GmshCall(G.gmshOptionSetNumber("Mesh.Smoothing", 0, &ierr_gmsh), "set Mesh.Smoothing");
  }
  GmshCall(view = G.gmshViewAdd("size", -1, &ierr_gmsh), "add the size view");
  GmshCall(G.gmshViewAddListData(view, dim == 2 ? "ST" : "SS", (int)ncells, data, (size_t)(ncells * nv * 4), &ierr_gmsh), "fill the size view");
  GmshCall(field = G.gmshModelMeshFieldAdd("PostView", -1, &ierr_gmsh), "add the size field");
  GmshCall(G.gmshModelMeshFieldSetNumber(field, "ViewTag", view, &ierr_gmsh), "set the size field's view");
  GmshCall(G.gmshModelMeshFieldSetAsBackgroundMesh(field, &ierr_gmsh), "set the background mesh");
  GmshCall(G.gmshModelMeshGenerate((int)dim, &ierr_gmsh), "mesh the model");
  if (out)
    GmshCall(G.gmshWrite(out, &ierr_gmsh), "write the mesh");
  else
    PetscCall(GmshTakeMesh(dim, made));
  GmshCall(G.gmshFinalize(&ierr_gmsh), "finish");
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The size at each local vertex (indexed by point from the chart's start): the smallest its cells ask for, over all
   ranks (the point SF's MIN at the owner, then sent back). */
static PetscErrorCode VertexSizes(DM dm, const PetscReal size[], PetscReal **vsize)
{
  PetscInt   pStart, pEnd, cStart, cEnd, nroots;
  PetscSF    sf;
  PetscReal *v;

  PetscFunctionBeginUser;
  PetscCall(DMPlexGetChart(dm, &pStart, &pEnd));
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  PetscCall(PetscMalloc1(pEnd - pStart, &v));
  for (PetscInt p = pStart; p < pEnd; ++p) v[p - pStart] = PETSC_MAX_REAL;
  for (PetscInt c = cStart; c < cEnd; ++c) {
    PetscInt verts[8], n;

    PetscCall(MeshCellVertices(dm, c, verts, &n));
    for (PetscInt k = 0; k < n; ++k) v[verts[k] - pStart] = PetscMin(v[verts[k] - pStart], size[c - cStart]);
  }
  PetscCall(DMGetPointSF(dm, &sf));
  PetscCall(PetscSFGetGraph(sf, &nroots, NULL, NULL, NULL));
  if (nroots >= 0) {
    PetscCall(PetscSFReduceBegin(sf, MPIU_REAL, v, v, MPI_MIN));
    PetscCall(PetscSFReduceEnd(sf, MPIU_REAL, v, v, MPI_MIN));
    PetscCall(PetscSFBcastBegin(sf, MPIU_REAL, v, v, MPI_REPLACE));
    PetscCall(PetscSFBcastEnd(sf, MPIU_REAL, v, v, MPI_REPLACE));
  }
  *vsize = v;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The cells' list data in the order of their centroids (lexicographic in x, y, z): the same on any partition. C's
   qsort() passes no context to its comparison: the data it compares are these file-scope variables, set by
   SortCells() on rank 0 just before the sort. */
static PetscInt      sort_per, sort_nv;
static const double *sort_data;
static int           CompareCentroids(const void *a, const void *b)
{
  const double *da = &sort_data[*(const PetscInt *)a * sort_per], *db = &sort_data[*(const PetscInt *)b * sort_per];

  for (PetscInt j = 0; j < 3; ++j) {
    double ca = 0.0, cb = 0.0;

    for (PetscInt k = 0; k < sort_nv; ++k) {
      ca += da[j * sort_nv + k];
      cb += db[j * sort_nv + k];
    }
    if (ca != cb) return ca < cb ? -1 : 1;
  }
  return 0;
}

static PetscErrorCode SortCells(PetscInt ncells, PetscInt nv, double data[])
{
  PetscInt      *order;
  double        *copy;
  const PetscInt per = 4 * nv;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc2(ncells, &order, ncells * per, &copy));
  for (PetscInt i = 0; i < ncells; ++i) order[i] = i;
  PetscCall(PetscArraycpy(copy, data, ncells * per));
  sort_per  = per;
  sort_nv   = nv;
  sort_data = copy;
  qsort(order, (size_t)ncells, sizeof(PetscInt), CompareCentroids);
  for (PetscInt i = 0; i < ncells; ++i) PetscCall(PetscArraycpy(&data[i * per], &copy[order[i] * per], per));
  PetscCall(PetscFree2(order, copy));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The "Face Sets" values the faces of dm carry, over all ranks: present[v] for v < *n (free with PetscFree). */
static PetscErrorCode FaceSetValues(DM dm, PetscInt *n, PetscBool **present)
{
  DMLabel         label;
  IS              is = NULL;
  PetscInt        nv = 0, vmax = -1;
  const PetscInt *v = NULL;
  PetscInt       *flag;

  PetscFunctionBeginUser;
  PetscCall(DMGetLabel(dm, "Face Sets", &label));
  if (label) {
    PetscCall(DMLabelGetNonEmptyStratumValuesIS(label, &is));
    PetscCall(ISGetLocalSize(is, &nv));
    PetscCall(ISGetIndices(is, &v));
  }
  for (PetscInt i = 0; i < nv; ++i) vmax = PetscMax(vmax, v[i]);
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &vmax, 1, MPIU_INT, MPI_MAX, PetscObjectComm((PetscObject)dm)));
  *n = vmax + 1;
  PetscCall(PetscCalloc1(*n + 1, &flag));
  for (PetscInt i = 0; i < nv; ++i)
    if (v[i] >= 0) flag[v[i]] = 1;
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, flag, *n, MPIU_INT, MPI_MAX, PetscObjectComm((PetscObject)dm)));
  PetscCall(PetscMalloc1(*n + 1, present));
  for (PetscInt i = 0; i < *n; ++i) (*present)[i] = (PetscBool)(flag[i] != 0);
  PetscCall(PetscFree(flag));
  if (is) {
    PetscCall(ISRestoreIndices(is, &v));
    PetscCall(ISDestroy(&is));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Every face set of the old mesh on the new one: a model that is not the mesh's would lose the boundary conditions. */
static PetscErrorCode CheckFaceSets(DM dm, DM remeshed, const char model[])
{
  PetscInt   n_old, n_new;
  PetscBool *old_sets, *new_sets;

  PetscFunctionBeginUser;
  PetscCall(FaceSetValues(dm, &n_old, &old_sets));
  PetscCall(FaceSetValues(remeshed, &n_new, &new_sets));
  for (PetscInt i = 0; i < n_old; ++i)
    PetscCheck(!old_sets[i] || (i < n_new && new_sets[i]), PetscObjectComm((PetscObject)dm), PETSC_ERR_USER_INPUT,
               "-adapt_model %s: the mesh Gmsh made of the model has no face in the face set %" PetscInt_FMT
               " (\"Face Sets\" value, a physical group's number) that the mesh had: is it the model of the mesh?",
               model[0] ? model : "(the box of the options)", i);
  PetscCall(PetscFree(old_sets));
  PetscCall(PetscFree(new_sets));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode MeshRemesh(DM dm, const char model[], const MeshBox *box, const PetscReal size[], Vec loc, DM *remeshed, MeshTransfer *tr)
{
  const PetscScalar *lu     = NULL;
  PetscSection       lsec   = NULL;
  PetscReal         *mine_u = NULL, *all_u = NULL, *all_x = NULL;
  MPI_Comm           comm = PetscObjectComm((PetscObject)dm);
  PetscMPIInt        rank, nranks, count, *counts = NULL, *displs = NULL;
  PetscInt           dim, cStart, cEnd, pStart, nv, per, total = 0;
  PetscReal         *vsize = NULL;
  double            *mine, *all = NULL;
  char               out[PETSC_MAX_PATH_LEN] = "", why[512] = "", what[PETSC_MAX_PATH_LEN + 64];
  MeshSimplices      made;
  int                failed = 0;
  PetscSection       csec;
  Vec                coords;
  const PetscScalar *xc;

  PetscFunctionBeginUser;
  PetscCall(PetscMemzero(&made, sizeof(made)));
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCallMPI(MPI_Comm_size(comm, &nranks));
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  PetscCall(DMPlexGetChart(dm, &pStart, NULL));
  nv  = dim + 1;
  per = 4 * nv; /* x, y, z of each vertex, then its value */
  if (dim == 3) PetscCall(VertexSizes(dm, size, &vsize));
  PetscCall(DMGetCoordinateSection(dm, &csec));
  PetscCall(DMGetCoordinatesLocal(dm, &coords));
  PetscCall(VecGetArrayRead(coords, &xc));
  PetscCall(PetscCalloc1((cEnd - cStart) * per + 1, &mine));
  if (loc) { /* the field at each cell's vertices, for the transfer */
    PetscCall(DMGetLocalSection(dm, &lsec));
    PetscCall(VecGetArrayRead(loc, &lu));
    PetscCall(PetscCalloc1((cEnd - cStart) * nv * dim + 1, &mine_u));
  }
  for (PetscInt c = cStart; c < cEnd; ++c) {
    double  *d = &mine[(c - cStart) * per];
    PetscInt verts[8], n;

    PetscCall(MeshCellVertices(dm, c, verts, &n));
    PetscCheck(n == nv, comm, PETSC_ERR_SUP, "-adapt_model remeshes simplices (triangles, tetrahedra) only");
    for (PetscInt k = 0; k < nv; ++k) {
      PetscInt off;

      PetscCall(PetscSectionGetOffset(csec, verts[k], &off));
      for (PetscInt j = 0; j < dim; ++j) d[j * nv + k] = PetscRealPart(xc[off + j]);
      d[3 * nv + k] = vsize ? vsize[verts[k] - pStart] : size[c - cStart];
      if (loc) {
        PetscInt ndof;

        PetscCall(PetscSectionGetDof(lsec, verts[k], &ndof));
        PetscCall(PetscSectionGetOffset(lsec, verts[k], &off));
        for (PetscInt j = 0; j < dim && j < ndof; ++j) mine_u[((c - cStart) * nv + k) * dim + j] = PetscRealPart(lu[off + j]);
      }
    }
  }
  PetscCall(VecRestoreArrayRead(coords, &xc));
  if (loc) PetscCall(VecRestoreArrayRead(loc, &lu));
  PetscCall(PetscFree(vsize));
  PetscCall(PetscMPIIntCast((cEnd - cStart) * per, &count));
  if (rank == 0) PetscCall(PetscMalloc2(nranks, &counts, nranks, &displs));
  PetscCallMPI(MPI_Gather(&count, 1, MPI_INT, counts, 1, MPI_INT, 0, comm));
  if (rank == 0) {
    for (PetscMPIInt r = 0; r < nranks; ++r) {
      displs[r] = (PetscMPIInt)total;
      total += counts[r];
    }
    PetscCall(PetscMalloc1(total + 1, &all));
  }
  PetscCallMPI(MPI_Gatherv(mine, count, MPI_DOUBLE, all, counts, displs, MPI_DOUBLE, 0, comm));
  PetscCall(PetscFree(mine));
  if (loc) { /* the same cells' fields, nv * dim values for per = 4 nv of the sizes' data */
    PetscMPIInt count_u, *counts_u = NULL, *displs_u = NULL;

    PetscCall(PetscMPIIntCast((cEnd - cStart) * nv * dim, &count_u));
    if (rank == 0) {
      PetscCall(PetscMalloc2(nranks, &counts_u, nranks, &displs_u));
      for (PetscMPIInt r = 0; r < nranks; ++r) {
        counts_u[r] = (PetscMPIInt)(counts[r] / per * nv * dim);
        displs_u[r] = (PetscMPIInt)(displs[r] / per * nv * dim);
      }
      PetscCall(PetscMalloc1(total / per * nv * dim + 1, &all_u));
      PetscCall(PetscMalloc1(total / per * nv * dim + 1, &all_x));
      for (PetscInt c = 0; c < total / per; ++c) /* the vertices' positions, before the sort (the transfer takes any order) */
        for (PetscInt k = 0; k < nv; ++k)
          for (PetscInt j = 0; j < dim; ++j) all_x[(c * nv + k) * dim + j] = all[c * per + j * nv + k];
    }
    PetscCallMPI(MPI_Gatherv(mine_u, count_u, MPIU_REAL, all_u, counts_u, displs_u, MPIU_REAL, 0, comm));
    PetscCall(PetscFree(mine_u));
    if (rank == 0) PetscCall(PetscFree2(counts_u, displs_u));
  }
  if (rank == 0) {
    char tmp[PETSC_MAX_PATH_LEN];

    PetscCall(SortCells(total / per, nv, all));
    if (box->petsc_read) { /* for comparison: Gmsh writes the mesh, PETSc's reader reads it */
      PetscCall(PetscGetTmp(PETSC_COMM_SELF, tmp, sizeof(tmp)));
      PetscCall(PetscSNPrintf(out, sizeof(out), "%s/signorini-remesh-%d.msh", tmp, (int)getpid()));
    }
    PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
    failed = GmshRemesh(model, box, dim, total / per, nv, all, out[0] ? out : NULL, &made);
    PetscCall(PetscPopErrorHandler());
    if (failed) {
      const char *text     = NULL;
      char       *specific = NULL;
      int         ierr_gmsh;

      if (G.gmshFinalize) G.gmshFinalize(&ierr_gmsh); /* whatever state Gmsh was left in */
      PetscCall(PetscErrorMessage(failed, &text, &specific));
      PetscCall(PetscStrncpy(why, specific && specific[0] ? specific : text, sizeof(why)));
      if (out[0]) (void)unlink(out);
      PetscCall(MeshSimplicesReset(&made));
    }
    PetscCall(PetscFree(all));
    PetscCall(PetscFree2(counts, displs));
  }
  PetscCallMPI(MPI_Bcast(&failed, 1, MPI_INT, 0, comm));
  PetscCallMPI(MPI_Bcast(why, sizeof(why), MPI_CHAR, 0, comm));
  PetscCheck(!failed, comm, PETSC_ERR_LIB, "-adapt_model %s: %s", model[0] ? model : "(the box of the options)", why);
  PetscCall(PetscSNPrintf(what, sizeof(what), "the mesh Gmsh made of -adapt_model %s", model[0] ? model : "(the box of the options)"));
  if (box->petsc_read) {
    PetscCallMPI(MPI_Bcast(out, sizeof(out), MPI_CHAR, 0, comm));
    PetscCall(MeshReadRemeshedFile(comm, out, remeshed));
    PetscCallMPI(MPI_Barrier(comm));
    if (rank == 0) (void)unlink(out); /* read: removed before the checks, which may refuse the mesh */
  } else {
    PetscCall(MeshSimplicesBuild(comm, &made, remeshed));
    PetscCall(MeshSimplicesReset(&made));
  }
  PetscCall(MeshDistributeRemeshed(what, remeshed));
  PetscCall(CheckFaceSets(dm, *remeshed, model));
  if (loc) PetscCall(MeshTransferCreate(comm, dim, total / per, all_x, all_u, tr)); /* which owns all_x and all_u (rank 0) */
  {
    MatType mtype;

    PetscCall(DMGetMatType(dm, &mtype));
    PetscCall(DMSetMatType(*remeshed, mtype));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

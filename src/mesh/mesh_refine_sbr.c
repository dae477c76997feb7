/* Fast point lookups for PETSc 3.18's skeleton-based refinement (refine_sbr), which MeshRefineMarked() applies.

   The transform keeps each point's refinement type (a vertex, a kept or halved edge, a triangle kept or split in two,
   three or four) in a label, and DMPlexTransformApply() asks for it several times per new point: through the type's
   cell transform (which new points a point makes) and its subcell orientation. DMLabelGetValue() looks for the point in
   each of the label's up to 14 strata in turn, one binary search each (docs/decisions.md, "Refinement lookups"). The answers of both calls depend on
   the point only through its type:
   - the cell transform returns tables for its cell type and refinement type (in arrays that the split triangles'
     types share and rewrite at each call, so they are copied);
   - the orientation is a function of the refinement type and of the other arguments (the switch below).
   So the types are read into an array indexed by point once, after DMPlexTransformSetUp(); the cell transform is asked
   once per (cell type, refinement type) and its tables kept; and the orientation is the transform's own switch with
   the type read from the array. The new mesh is the same point for point. The types and the switch are PETSc 3.18's
   (plexrefsbr.c, BSD-2-Clause); another version keeps its own transform.

   The transform also finds a point's index in its stratum (DMLabelGetStratumPointIndex()) for every new point's source
   (DMPlexTransformGetTargetPoint()), through ISGetIndices(), which expands a stratum kept as a stride index set (the
   points contiguous: the vertices, the unrefined edges) into a new array at every call: the refinement took a time
   quadratic in the mesh's size.
   Such strata are made general index sets, with the same sorted points, on any version: each lookup a binary search.
   One of PETSc 3.18's mirrors (docs/decisions.md, "PETSc 3.18's mirrors"). */
#include <petscdmplextransform.h>
#include <petsc/private/dmplextransformimpl.h>
#include "mesh.h"

/* PETSc 3.18's refinement types of refine_sbr (src/dm/impls/plex/transform/impls/refine/sbr/plexrefsbr.c), in its order */
typedef enum {
  SBR_VERTEX,
  SBR_EDGE,
  SBR_EDGE_SPLIT,
  SBR_TRIANGLE,
  SBR_TRIANGLE_SPLIT,
  SBR_TRIANGLE_SPLIT_01,
  SBR_TRIANGLE_SPLIT_10,
  SBR_TRIANGLE_SPLIT_12,
  SBR_TRIANGLE_SPLIT_21,
  SBR_TRIANGLE_SPLIT_20,
  SBR_TRIANGLE_SPLIT_02,
  SBR_TRIANGLE_SPLIT_0,
  SBR_TRIANGLE_SPLIT_1,
  SBR_TRIANGLE_SPLIT_2,
  SBR_NUM_TYPES
} SBRType;

/* One answer of the cell transform, for a cell type and a refinement type: a copy of its tables */
typedef struct {
  PetscBool       known;
  PetscInt        Nt;
  DMPolytopeType *target;
  PetscInt       *size, *cone, *ornt;
} SBRAnswer;

/* a copies the transform's tables: Nt new point types, size[n] points of type target[n], each with the cone points of
   its type, each in cone[] as (type, number of levels up, that many indices, replica) and with one orientation */
static PetscErrorCode SBRAnswerCopy(PetscInt Nt, const DMPolytopeType target[], const PetscInt size[], const PetscInt cone[], const PetscInt ornt[],
                                    SBRAnswer *a)
{
  PetscInt nc = 0, no = 0;

  PetscFunctionBegin;
  for (PetscInt n = 0; n < Nt; ++n)
    for (PetscInt r = 0; r < size[n]; ++r)
      for (PetscInt k = 0; k < DMPolytopeTypeGetConeSize(target[n]); ++k, ++no) nc += 3 + cone[nc + 1];
  a->Nt = Nt;
  PetscCall(PetscMalloc4(Nt, &a->target, Nt, &a->size, nc, &a->cone, no, &a->ornt));
  PetscCall(PetscArraycpy(a->target, target, Nt));
  PetscCall(PetscArraycpy(a->size, size, Nt));
  PetscCall(PetscArraycpy(a->cone, cone, nc));
  PetscCall(PetscArraycpy(a->ornt, ornt, no));
  a->known = PETSC_TRUE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

typedef struct {
  PetscInt  pStart, pEnd;
  PetscInt *type; /* type[p - pStart]: the refinement type of point p, -1 if it has none */
  SBRAnswer answer[DM_NUM_POLYTOPES][SBR_NUM_TYPES];
  PetscErrorCode (*celltransform)(DMPlexTransform, DMPolytopeType, PetscInt, PetscInt *, PetscInt *, DMPolytopeType *[], PetscInt *[], PetscInt *[],
                                  PetscInt *[]);
  PetscErrorCode (*orientation)(DMPlexTransform, DMPolytopeType, PetscInt, PetscInt, DMPolytopeType, PetscInt, PetscInt, PetscInt *, PetscInt *);
} SBRLookup;

#define SBR_LOOKUP_KEY "MeshRefineSBRLookup"

static PetscErrorCode SBRLookupDestroy(void *ctx)
{
  SBRLookup *l = (SBRLookup *)ctx;

  PetscFunctionBegin;
  for (PetscInt ct = 0; ct < DM_NUM_POLYTOPES; ++ct)
    for (PetscInt t = 0; t < SBR_NUM_TYPES; ++t)
      if (l->answer[ct][t].known) PetscCall(PetscFree4(l->answer[ct][t].target, l->answer[ct][t].size, l->answer[ct][t].cone, l->answer[ct][t].ornt));
  PetscCall(PetscFree(l->type));
  PetscCall(PetscFree(l));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode SBRLookupGet(DMPlexTransform tr, SBRLookup **l)
{
  PetscContainer c;

  PetscFunctionBegin;
  PetscCall(PetscObjectQuery((PetscObject)tr, SBR_LOOKUP_KEY, (PetscObject *)&c));
  PetscCheck(c, PETSC_COMM_SELF, PETSC_ERR_PLIB, "the refinement's lookup table is missing");
  PetscCall(PetscContainerGetPointer(c, (void **)l));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscInt SBRLookupType(const SBRLookup *l, PetscInt p)
{
  return (p >= l->pStart && p < l->pEnd) ? l->type[p - l->pStart] : -1;
}

/* The cell transform: the tables of (source, the type of p), asked of refine_sbr's own once per pair */
static PetscErrorCode SBRCellTransform(DMPlexTransform tr, DMPolytopeType source, PetscInt p, PetscInt *rt, PetscInt *Nt, DMPolytopeType *target[],
                                       PetscInt *size[], PetscInt *cone[], PetscInt *ornt[])
{
  SBRLookup *l;
  SBRAnswer *a;
  PetscInt   t;

  PetscFunctionBeginHot;
  PetscCall(SBRLookupGet(tr, &l));
  t = SBRLookupType(l, p);
  if (t < 0 || t >= SBR_NUM_TYPES || source < 0 || source >= DM_NUM_POLYTOPES) {
    PetscCall(l->celltransform(tr, source, p, rt, Nt, target, size, cone, ornt));
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  a = &l->answer[source][t];
  if (!a->known) {
    PetscInt        got, n, *s, *cn, *o;
    DMPolytopeType *tg;

    PetscCall(l->celltransform(tr, source, p, &got, &n, &tg, &s, &cn, &o));
    PetscCheck(got == t, PETSC_COMM_SELF, PETSC_ERR_PLIB, "point %" PetscInt_FMT " has refinement type %" PetscInt_FMT ", the lookup %" PetscInt_FMT,
               p, got, t);
    PetscCall(SBRAnswerCopy(n, tg, s, cn, o, a));
  }
  if (rt) *rt = t;
  *Nt     = a->Nt;
  *target = a->target;
  *size   = a->size;
  *cone   = a->cone;
  *ornt   = a->ornt;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The orientation of subcell (tct, r) with orientation o of source point sp with orientation so: refine_sbr's
   DMPlexTransformGetSubcellOrientation_SBR(), with sp's type from the lookup */
static PetscErrorCode SBRSubcellOrientation(DMPlexTransform tr, DMPolytopeType sct, PetscInt sp, PetscInt so, DMPolytopeType tct, PetscInt r,
                                            PetscInt o, PetscInt *rnew, PetscInt *onew)
{
  SBRLookup *l;
  PetscInt   t;

  PetscFunctionBeginHot;
  PetscCall(SBRLookupGet(tr, &l));
  t = SBRLookupType(l, sp);
  if (t < 0) {
    PetscCall(l->orientation(tr, sct, sp, so, tct, r, o, rnew, onew));
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  *rnew = r;
  *onew = o;
  switch (t) {
    case SBR_TRIANGLE_SPLIT_01:
    case SBR_TRIANGLE_SPLIT_10:
    case SBR_TRIANGLE_SPLIT_12:
    case SBR_TRIANGLE_SPLIT_21:
    case SBR_TRIANGLE_SPLIT_20:
    case SBR_TRIANGLE_SPLIT_02:
      break;
    case SBR_TRIANGLE_SPLIT_0:
    case SBR_TRIANGLE_SPLIT_1:
    case SBR_TRIANGLE_SPLIT_2:
      if (tct == DM_POLYTOPE_TRIANGLE) {
        *onew = so < 0 ? -(o + 1) : o;
        *rnew = so < 0 ? (r + 1) % 2 : r;
      }
      break;
    case SBR_EDGE_SPLIT:
    case SBR_TRIANGLE_SPLIT:
      PetscCall(DMPlexTransformGetSubcellOrientation_Regular(tr, sct, sp, so, tct, r, o, rnew, onew));
      break;
    default:
      PetscCall(DMPlexTransformGetSubcellOrientationIdentity(tr, sct, sp, so, tct, r, o, rnew, onew));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* After DMPlexTransformSetUp() of a refine_sbr transform: its strata made general index sets, and on PETSc 3.18 its
   types read into an array and its cell transform and subcell orientation replaced by the lookups above. */
PetscErrorCode MeshRefineSBRLookups(DMPlexTransform tr)
{
  const PetscBool lookups = PETSC_VERSION_EQ(3, 18, PETSC_VERSION_SUBMINOR);
  DMLabel         types   = tr->trType;
  SBRLookup      *l       = NULL;
  IS              values;
  const PetscInt *vals;
  PetscInt        nv;

  PetscFunctionBeginUser;
  if (!types) PetscFunctionReturn(PETSC_SUCCESS);
  if (lookups) {
    PetscCall(PetscNew(&l));
    PetscCall(DMPlexGetChart(tr->dm, &l->pStart, &l->pEnd));
    PetscCall(PetscMalloc1(l->pEnd - l->pStart, &l->type));
    for (PetscInt p = 0; p < l->pEnd - l->pStart; ++p) l->type[p] = -1;
  }
  PetscCall(DMLabelGetValueIS(types, &values));
  PetscCall(ISGetLocalSize(values, &nv));
  PetscCall(ISGetIndices(values, &vals));
  for (PetscInt k = 0; k < nv; ++k) {
    IS              is, general;
    PetscBool       stride;
    PetscInt        n;
    const PetscInt *pts;

    PetscCall(DMLabelGetStratumIS(types, vals[k], &is));
    if (!is) continue;
    PetscCall(ISGetLocalSize(is, &n));
    PetscCall(ISGetIndices(is, &pts));
    PetscCall(PetscObjectTypeCompare((PetscObject)is, ISSTRIDE, &stride));
    if (stride) {
      PetscCall(ISCreateGeneral(PETSC_COMM_SELF, n, pts, PETSC_COPY_VALUES, &general));
      PetscCall(DMLabelSetStratumIS(types, vals[k], general));
      PetscCall(ISDestroy(&general));
    }
    if (lookups) {
      PetscCheck(vals[k] >= 0 && vals[k] < SBR_NUM_TYPES, PETSC_COMM_SELF, PETSC_ERR_PLIB, "refine_sbr gave the refinement type %" PetscInt_FMT,
                 vals[k]);
      for (PetscInt i = 0; i < n; ++i)
        if (pts[i] >= l->pStart && pts[i] < l->pEnd) l->type[pts[i] - l->pStart] = vals[k];
    }
    PetscCall(ISRestoreIndices(is, &pts));
    PetscCall(ISDestroy(&is));
  }
  PetscCall(ISRestoreIndices(values, &vals));
  PetscCall(ISDestroy(&values));
  if (lookups) {
    PetscContainer c;

    l->celltransform = tr->ops->celltransform;
    l->orientation   = tr->ops->getsubcellorientation;
    PetscCall(PetscContainerCreate(PETSC_COMM_SELF, &c));
    PetscCall(PetscContainerSetPointer(c, l));
    PetscCall(PetscContainerSetUserDestroy(c, SBRLookupDestroy));
    PetscCall(PetscObjectCompose((PetscObject)tr, SBR_LOOKUP_KEY, (PetscObject)c));
    PetscCall(PetscContainerDestroy(&c));
    tr->ops->celltransform         = SBRCellTransform;
    tr->ops->getsubcellorientation = SBRSubcellOrientation;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

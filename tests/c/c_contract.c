/* c_contract.c: the C API contract, from C99.
 *
 * Calls every exported function with NULL for each pointer, too-small arenas
 * and root buffers, bad and misaligned strides and pointers, NaN/Inf input,
 * out-of-range indices and bad maps, and checks for each call:
 *   - the documented PelageStatus,
 *   - a non-empty pelage_last_error() and a non-NULL pelage_status_string(),
 *   - that every output buffer (pre-filled with 0xCD canary bytes) is left
 *     untouched, except *root_count on CAPACITY_EXCEEDED from a short root
 *     buffer, which reports the count needed (documented).
 * Then the success path on a UV sphere: counts, ranges, ranks, ids, root
 * positions on their triangles, determinism, strided outputs, maps.
 *
 * Bad inputs are memory-safe: a buffer declared with stride 13 really holds
 * elements 13 bytes apart, so a missing check shows up as a wrong status,
 * not as an out-of-bounds read. Failed checks are counted, not fatal. */
#include <pelage.h>

#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* --- A tiny check framework ------------------------------------------------ */

static int g_checks, g_failures;

#define CHECK(cond)                                                                                     \
  do {                                                                                                  \
    ++g_checks;                                                                                         \
    if (!(cond)) {                                                                                      \
      ++g_failures;                                                                                     \
      fprintf(stderr, "%s:%d: CHECK(%s) failed; pelage_last_error: \"%s\"\n", __FILE__, __LINE__, #cond, \
              pelage_last_error());                                                                     \
    }                                                                                                   \
  } while (0)

/* Stops the run when a precondition of the following checks does not hold. */
#define REQUIRE(cond)                                                                                   \
  do {                                                                                                  \
    const int required_ = (cond) ? 1 : 0; /* evaluated once */                                          \
    CHECK(required_);                                                                                   \
    if (!required_) {                                                                                   \
      fprintf(stderr, "%s:%d: REQUIRE(%s) failed, cannot continue\n", __FILE__, __LINE__, #cond);        \
      exit(1);                                                                                          \
    }                                                                                                   \
  } while (0)

static const char *status_name(int s) {
  static const char *names[] = {"OK",          "NULL_PARAMETER",  "INVALID_ARGUMENT", "NON_FINITE",
                                "OUT_OF_RANGE", "CAPACITY_EXCEEDED", "MISALIGNED",      "CORRUPT_DATA",
                                "VERSION_MISMATCH", "CANCELLED",   "PANIC"};
  return s >= 0 && s <= 10 ? names[s] : "(unknown)";
}

/* Checks a call's status; on expected failure also checks the error message. */
static void expect_(const char *file, int line, const char *what, PelageStatus got, PelageStatus want) {
  const char *message = pelage_last_error();
  ++g_checks;
  if (got != want) {
    ++g_failures;
    fprintf(stderr, "%s:%d: %s: got %s, want %s; pelage_last_error: \"%s\"\n", file, line, what,
            status_name(got), status_name(want), message ? message : "(NULL)");
    return;
  }
  if (pelage_status_string(got) == NULL) {
    ++g_failures;
    fprintf(stderr, "%s:%d: %s: pelage_status_string(%d) is NULL\n", file, line, what, (int)got);
  }
  if (want != PELAGE_STATUS_OK && (message == NULL || message[0] == '\0')) {
    ++g_failures;
    fprintf(stderr, "%s:%d: %s: failed with %s but pelage_last_error() is empty\n", file, line, what,
            status_name(got));
  }
}
#define EXPECT(want, call) expect_(__FILE__, __LINE__, #call, (call), (want))

#define CANARY 0xCD
static int untouched(const void *p, size_t n) {
  const unsigned char *b = (const unsigned char *)p;
  for (size_t i = 0; i < n; ++i) {
    if (b[i] != CANARY) return 0;
  }
  return 1;
}
#define FILL(p, n) memset((p), CANARY, (n))

/* --- Test meshes ------------------------------------------------------------ */

/* A UV sphere with a duplicated seam column and pole rows of repeated points,
 * so the pole bands hold 2 * cols zero-area triangles. uv = (c / cols, r / rows). */
typedef struct Sphere {
  float (*p)[3];
  float (*uv)[2];
  float (*n)[3];
  uint32_t (*t)[3];
  size_t nv, nt;
  int rows, cols;
} Sphere;

static Sphere sphere_new(int rows, int cols) {
  Sphere s;
  s.rows = rows, s.cols = cols;
  s.nv = (size_t)(rows + 1) * (size_t)(cols + 1);
  s.nt = 2u * (size_t)rows * (size_t)cols;
  s.p = malloc(s.nv * sizeof *s.p);
  s.uv = malloc(s.nv * sizeof *s.uv);
  s.n = malloc(s.nv * sizeof *s.n);
  s.t = malloc(s.nt * sizeof *s.t);
  REQUIRE(s.p && s.uv && s.n && s.t);
  const double pi = 3.14159265358979323846;
  for (int r = 0; r <= rows; ++r) {
    const double th = pi * r / rows;
    for (int c = 0; c <= cols; ++c) {
      const double ph = 2.0 * pi * (c % cols) / cols;
      const size_t i = (size_t)r * (size_t)(cols + 1) + (size_t)c;
      const double st = (r == 0 || r == rows) ? 0.0 : sin(th);
      s.p[i][0] = (float)(st * cos(ph));
      s.p[i][1] = (float)(r == 0 ? 1.0 : r == rows ? -1.0 : cos(th));
      s.p[i][2] = (float)(-st * sin(ph));
      memcpy(s.n[i], s.p[i], sizeof s.n[i]);
      s.uv[i][0] = (float)c / (float)cols;
      s.uv[i][1] = (float)r / (float)rows;
    }
  }
  size_t k = 0;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const uint32_t a = (uint32_t)(r * (cols + 1) + c), b = a + 1, d = a + (uint32_t)cols + 1, e = d + 1;
      /* counter-clockwise seen from outside */
      s.t[k][0] = a, s.t[k][1] = d, s.t[k][2] = e, ++k;
      s.t[k][0] = a, s.t[k][1] = e, s.t[k][2] = b, ++k;
    }
  }
  return s;
}

static void sphere_free(Sphere *s) {
  free(s->p), free(s->uv), free(s->n), free(s->t);
}

static PelageMeshDesc sphere_desc(const Sphere *s) {
  PelageMeshDesc m;
  memset(&m, 0, sizeof m);
  m.positions = s->p, m.position_stride = sizeof s->p[0], m.vertex_count = s->nv;
  m.indices = s->t, m.index_stride = sizeof s->t[0], m.triangle_count = s->nt;
  m.uvs = s->uv, m.uv_stride = sizeof s->uv[0];
  m.normals = s->n, m.normal_stride = sizeof s->n[0];
  return m;
}

/* A copy of `count` elements of `size` bytes placed `stride` bytes apart,
 * starting `offset` bytes into a fresh allocation (for bad strides and
 * misaligned pointers that are still memory-safe). Freed by scratch_free. */
static void *g_scratch[64];
static int g_scratch_n;
static const void *restride(const void *src, size_t size, size_t count, size_t stride, size_t offset) {
  const size_t step = stride > size ? stride : size;
  unsigned char *buf = calloc(offset + step * count + 16, 1);
  REQUIRE(buf && g_scratch_n < 64);
  g_scratch[g_scratch_n++] = buf;
  for (size_t i = 0; i < count; ++i) memcpy(buf + offset + i * stride, (const unsigned char *)src + i * size, size);
  return buf + offset;
}
static void scratch_free(void) {
  while (g_scratch_n > 0) free(g_scratch[--g_scratch_n]);
}

/* --- Shared state for the failure cases --------------------------------------- */

static Sphere g_sphere;
static PelageStampParams g_params;   /* valid parameters (target 3000) */
static unsigned char *g_arena;        /* large enough for g_params on g_sphere */
static size_t g_arena_bytes;
static PelageRoot *g_roots;           /* the reference result */
static size_t g_count, g_capacity;

/* Runs stamp_query, stamp and (optionally) roots_evaluate on `mesh` with
 * otherwise valid arguments; each must fail with `want`, outputs untouched. */
static void bad_mesh_(int line, const char *name, const PelageMeshDesc *mesh, const PelageStampParams *params,
                      PelageStatus want, int evaluate) {
  char what[160];
  size_t sizes[2];
  FILL(sizes, sizeof sizes);
  snprintf(what, sizeof what, "%s: pelage_stamp_query", name);
  expect_(__FILE__, line, what, pelage_stamp_query(mesh, params, &sizes[0], &sizes[1]), want);
  if (!untouched(sizes, sizeof sizes)) ++g_failures, fprintf(stderr, "%s:%d: %s wrote its outputs\n", __FILE__, line, what);

  PelageRoot *roots = malloc(g_capacity * sizeof *roots);
  size_t count;
  PelageStampInfo info;
  REQUIRE(roots);
  FILL(roots, g_capacity * sizeof *roots), FILL(&count, sizeof count), FILL(&info, sizeof info);
  snprintf(what, sizeof what, "%s: pelage_stamp", name);
  expect_(__FILE__, line, what,
          pelage_stamp(mesh, params, g_arena, g_arena_bytes, roots, g_capacity, &count, &info), want);
  if (!untouched(roots, g_capacity * sizeof *roots) || !untouched(&count, sizeof count) ||
      !untouched(&info, sizeof info)) {
    ++g_failures, fprintf(stderr, "%s:%d: %s wrote its outputs\n", __FILE__, line, what);
  }
  free(roots);

  if (evaluate) {
    const size_t bytes = g_count * 12;
    float *pos = malloc(bytes), *nrm = malloc(bytes);
    REQUIRE(pos && nrm);
    FILL(pos, bytes), FILL(nrm, bytes);
    snprintf(what, sizeof what, "%s: pelage_roots_evaluate", name);
    expect_(__FILE__, line, what, pelage_roots_evaluate(mesh, g_roots, g_count, pos, 12, nrm, 12), want);
    if (!untouched(pos, bytes) || !untouched(nrm, bytes)) {
      ++g_failures, fprintf(stderr, "%s:%d: %s wrote its outputs\n", __FILE__, line, what);
    }
    free(pos), free(nrm);
  }
}
#define BAD_MESH(name, mesh, want) bad_mesh_(__LINE__, name, &(mesh), &g_params, want, 1)
#define BAD_PARAMS(name, mesh, params, want) bad_mesh_(__LINE__, name, &(mesh), &(params), want, 0)

/* pelage_roots_evaluate with the given roots/outputs must fail with `want`
 * and leave both output buffers (canary-filled by the caller) untouched. */
static void bad_evaluate_(int line, const char *what, PelageStatus got, PelageStatus want, const void *pos,
                          size_t pos_bytes, const void *nrm, size_t nrm_bytes) {
  expect_(__FILE__, line, what, got, want);
  ++g_checks;
  if ((pos && !untouched(pos, pos_bytes)) || (nrm && !untouched(nrm, nrm_bytes))) {
    ++g_failures, fprintf(stderr, "%s:%d: %s wrote its outputs\n", __FILE__, line, what);
  }
}

/* --- Sections --------------------------------------------------------------------- */

static void test_version_and_strings(void) {
  CHECK(pelage_version() == PELAGE_VERSION_MAJOR * 10000u + PELAGE_VERSION_MINOR * 100u + PELAGE_VERSION_PATCH);
  for (int s = -3; s <= 12; ++s) {
    const char *str = pelage_status_string(s);
    CHECK(str != NULL && str[0] != '\0');
  }
  for (int s = 1; s <= 10; ++s) { /* every defined code has its own message */
    CHECK(strcmp(pelage_status_string(s), pelage_status_string(0)) != 0);
    CHECK(strcmp(pelage_status_string(s), pelage_status_string(999)) != 0);
  }
  const int unknown[] = {999, -1, 11, INT32_MAX, INT32_MIN};
  for (size_t i = 0; i < sizeof unknown / sizeof unknown[0]; ++i) {
    const char *str = pelage_status_string(unknown[i]);
    CHECK(str != NULL && str[0] != '\0');
  }
  printf("status strings: 0 \"%s\", 5 \"%s\", 999 \"%s\"\n", pelage_status_string(0), pelage_status_string(5),
         pelage_status_string(999));
  CHECK(pelage_last_error() != NULL);
}

static void test_defaults(void) {
  const PelageStampParams d = pelage_stamp_params_defaults();
  CHECK(d.target_count == 0);
  CHECK(d.seed == 0);
  CHECK(d.density.kind == PELAGE_MAP_KIND_CONSTANT && d.density.constant == 1.0f);
  CHECK(d.black_scale == 0.5f);
  CHECK(d.bald_below == 1.0f / 512.0f);
}

/* The reference stamp on the sphere, and the success-path invariants. */
static void test_success(void) {
  const PelageMeshDesc mesh = sphere_desc(&g_sphere);
  g_params = pelage_stamp_params_defaults();
  g_params.target_count = 3000;
  g_params.seed = 42;
  size_t arena_bytes = 0, max_roots = 0;
  EXPECT(PELAGE_STATUS_OK, pelage_stamp_query(&mesh, &g_params, &arena_bytes, &max_roots));
  REQUIRE(arena_bytes > 0 && max_roots >= g_params.target_count);
  g_arena_bytes = arena_bytes;
  g_arena = malloc(arena_bytes + 8);
  g_capacity = max_roots;
  g_roots = malloc(max_roots * sizeof *g_roots);
  REQUIRE(g_arena && g_roots);
  PelageStampInfo info;
  FILL(&info, sizeof info);
  EXPECT(PELAGE_STATUS_OK, pelage_stamp(&mesh, &g_params, g_arena, arena_bytes, g_roots, max_roots, &g_count, &info));
  REQUIRE(g_count > 0 && g_count <= max_roots);
  const char *after_ok = pelage_last_error();
  CHECK(after_ok != NULL);
  printf("sphere: %zu vertices, %zu triangles; arena %zu bytes, max_roots %zu\n", g_sphere.nv, g_sphere.nt,
         arena_bytes, max_roots);
  printf("stamped %zu roots (target %u): radius %.5f, %u passes, %u candidates, %u pruned, %u degenerate\n",
         g_count, g_params.target_count, info.radius, info.passes, info.candidates, info.pruned,
         info.degenerate_triangles);

  /* count within 3% of the target */
  CHECK(fabs((double)g_count - 3000.0) <= 0.03 * 3000.0);
  CHECK(info.radius > 0.0f && info.passes >= 1 && info.candidates >= g_count);
  CHECK(info.degenerate_triangles == 2u * (unsigned)g_sphere.cols); /* the two pole bands */

  /* faces in range, not degenerate; u, v in the triangle; ids = index; ranks a permutation */
  unsigned char *seen = calloc(g_count, 1);
  REQUIRE(seen);
  size_t bad_face = 0, bad_uv = 0, bad_id = 0, bad_rank = 0, on_degenerate = 0;
  const size_t band = (size_t)g_sphere.cols * 2u;
  for (size_t i = 0; i < g_count; ++i) {
    const PelageRoot r = g_roots[i];
    if (r.face >= g_sphere.nt) {
      ++bad_face;
      continue;
    }
    if (!(r.u >= 0.0f && r.v >= 0.0f && r.u + r.v <= 1.0f)) ++bad_uv;
    if (r.id != i) ++bad_id;
    if (r.rank >= g_count || seen[r.rank]++) ++bad_rank;
    /* degenerate: the second triangle of each cell in the top band, the first in the bottom band */
    if ((r.face < band && r.face % 2 == 1) || (r.face >= g_sphere.nt - band && r.face % 2 == 0)) ++on_degenerate;
  }
  free(seen);
  CHECK(bad_face == 0);
  CHECK(bad_uv == 0);
  CHECK(bad_id == 0);
  CHECK(bad_rank == 0);
  CHECK(on_degenerate == 0);
  size_t out_of_order = 0;
  for (size_t i = 1; i < g_count; ++i) out_of_order += g_roots[i - 1].face > g_roots[i].face;
  CHECK(out_of_order == 0); /* documented: roots come in face order */

  /* evaluated positions lie on their triangles; normals are unit and outward */
  float *pos = malloc(g_count * 16), *nrm = malloc(g_count * 12);
  REQUIRE(pos && nrm);
  FILL(pos, g_count * 16);
  EXPECT(PELAGE_STATUS_OK, pelage_roots_evaluate(&mesh, g_roots, g_count, pos, 16, nrm, 12));
  double worst = 0.0, worst_plane = 0.0, worst_normal = 0.0;
  size_t padding_written = 0;
  for (size_t i = 0; i < g_count; ++i) {
    const PelageRoot r = g_roots[i];
    const float *a = g_sphere.p[g_sphere.t[r.face][0]], *b = g_sphere.p[g_sphere.t[r.face][1]],
                *c = g_sphere.p[g_sphere.t[r.face][2]];
    const float *p = pos + 4 * i, *n = nrm + 3 * i;
    double e1[3], e2[3], fn[3], d = 0.0, plane = 0.0, len = 0.0, nl = 0.0, out = 0.0;
    for (int k = 0; k < 3; ++k) {
      const double ref = (1.0 - r.u - r.v) * a[k] + (double)r.u * b[k] + (double)r.v * c[k];
      d += (p[k] - ref) * (p[k] - ref);
      e1[k] = (double)b[k] - a[k], e2[k] = (double)c[k] - a[k];
      nl += (double)n[k] * n[k];
      out += (double)n[k] * p[k];
    }
    fn[0] = e1[1] * e2[2] - e1[2] * e2[1], fn[1] = e1[2] * e2[0] - e1[0] * e2[2], fn[2] = e1[0] * e2[1] - e1[1] * e2[0];
    for (int k = 0; k < 3; ++k) len += fn[k] * fn[k], plane += fn[k] * ((double)p[k] - a[k]);
    plane = fabs(plane) / sqrt(len);
    if (sqrt(d) > worst) worst = sqrt(d);
    if (plane > worst_plane) worst_plane = plane;
    if (fabs(sqrt(nl) - 1.0) > worst_normal) worst_normal = fabs(sqrt(nl) - 1.0);
    CHECK(out > 0.0);
    if (!untouched(p + 3, 4)) ++padding_written;
  }
  printf("evaluate: max |p - barycentric| %.2e, max distance to plane %.2e, max ||n| - 1| %.2e\n", worst,
         worst_plane, worst_normal);
  CHECK(worst < 1e-5);
  CHECK(worst_plane < 1e-5);
  CHECK(worst_normal < 1e-4);
  CHECK(padding_written == 0); /* stride 16: the 4th float of each slot is not written */

  /* positions only: normals may be NULL */
  EXPECT(PELAGE_STATUS_OK, pelage_roots_evaluate(&mesh, g_roots, g_count, pos, 12, NULL, 0));
  /* an empty range with NULL buffers is valid */
  EXPECT(PELAGE_STATUS_OK, pelage_roots_evaluate(&mesh, NULL, 0, NULL, 0, NULL, 0));
  free(pos), free(nrm);

  /* determinism: same seed same bits, at any arena alignment; another seed differs */
  PelageRoot *again = malloc(max_roots * sizeof *again);
  REQUIRE(again);
  for (size_t offset = 0; offset < 4; ++offset) {
    size_t n = 0;
    FILL(again, max_roots * sizeof *again);
    EXPECT(PELAGE_STATUS_OK,
           pelage_stamp(&mesh, &g_params, g_arena + offset, arena_bytes, again, max_roots, &n, NULL));
    CHECK(n == g_count && memcmp(again, g_roots, n * sizeof *again) == 0);
    CHECK(untouched(again + n, (max_roots - n) * sizeof *again)); /* nothing past the count */
  }
  PelageStampParams other = g_params;
  other.seed = 43;
  size_t n = 0;
  EXPECT(PELAGE_STATUS_OK, pelage_stamp(&mesh, &other, g_arena, arena_bytes, again, max_roots, &n, NULL));
  CHECK(n != g_count || memcmp(again, g_roots, n * sizeof *again) != 0);
  free(again);

  /* target 0 stamps nothing */
  other = g_params;
  other.target_count = 0;
  n = 99;
  EXPECT(PELAGE_STATUS_OK, pelage_stamp(&mesh, &other, g_arena, arena_bytes, NULL, 0, &n, NULL));
  CHECK(n == 0);
}

/* Density maps that make part of the sphere bald. */
static void test_maps(void) {
  const PelageMeshDesc mesh = sphere_desc(&g_sphere);
  /* per-vertex: 0 below the equator; width/height are unused for this kind */
  float *values = malloc(g_sphere.nv * sizeof *values);
  REQUIRE(values);
  for (size_t i = 0; i < g_sphere.nv; ++i) values[i] = g_sphere.p[i][1] >= 0.0f ? 1.0f : 0.0f;
  PelageStampParams p = g_params;
  p.density.kind = PELAGE_MAP_KIND_PER_VERTEX;
  p.density.data = values;
  p.density.stride = sizeof *values;
  p.density.width = 0, p.density.height = 0;
  PelageRoot *roots = malloc(g_capacity * 2 * sizeof *roots);
  size_t n = 0, arena_bytes = 0, max_roots = 0;
  REQUIRE(roots);
  EXPECT(PELAGE_STATUS_OK, pelage_stamp_query(&mesh, &p, &arena_bytes, &max_roots));
  unsigned char *arena = malloc(arena_bytes);
  REQUIRE(arena && max_roots <= 2 * g_capacity);
  EXPECT(PELAGE_STATUS_OK, pelage_stamp(&mesh, &p, arena, arena_bytes, roots, max_roots, &n, NULL));
  float *pos = malloc(n * 12 + 12);
  REQUIRE(pos);
  EXPECT(PELAGE_STATUS_OK, pelage_roots_evaluate(&mesh, roots, n, pos, 12, NULL, 0));
  float lowest = 1.0f;
  for (size_t i = 0; i < n; ++i) lowest = pos[3 * i + 1] < lowest ? pos[3 * i + 1] : lowest;
  printf("per-vertex map (bald below the equator): %zu roots, lowest y %.3f\n", n, lowest);
  CHECK(fabs((double)n - 3000.0) <= 0.03 * 3000.0);
  CHECK(lowest > -0.2f); /* a band of mixed triangles at most */
  free(pos), free(arena);

  /* texture: 8 x 2 texels, the u < 0.5 half black */
  const unsigned char tex[16] = {0, 0, 0, 0, 255, 255, 255, 255, 0, 0, 0, 0, 255, 255, 255, 255};
  p.density.kind = PELAGE_MAP_KIND_TEXTURE_U8;
  p.density.data = tex;
  p.density.width = 8, p.density.height = 2, p.density.stride = 8;
  EXPECT(PELAGE_STATUS_OK, pelage_stamp_query(&mesh, &p, &arena_bytes, &max_roots));
  arena = malloc(arena_bytes);
  REQUIRE(arena && max_roots <= 2 * g_capacity);
  EXPECT(PELAGE_STATUS_OK, pelage_stamp(&mesh, &p, arena, arena_bytes, roots, max_roots, &n, NULL));
  float min_u = 1.0f;
  for (size_t i = 0; i < n; ++i) {
    const uint32_t *t = g_sphere.t[roots[i].face];
    const float u = (1.0f - roots[i].u - roots[i].v) * g_sphere.uv[t[0]][0] + roots[i].u * g_sphere.uv[t[1]][0] +
                    roots[i].v * g_sphere.uv[t[2]][0];
    min_u = u < min_u ? u : min_u;
  }
  printf("texture map (bald for u < 0.5): %zu roots, lowest u %.3f\n", n, min_u);
  CHECK(fabs((double)n - 3000.0) <= 0.03 * 3000.0);
  CHECK(min_u > 0.4f);
  free(arena), free(roots), free(values);
}

static void test_null_pointers(void) {
  const PelageMeshDesc mesh = sphere_desc(&g_sphere);
  size_t a, b;
  FILL(&a, sizeof a), FILL(&b, sizeof b);
  EXPECT(PELAGE_STATUS_NULL_PARAMETER, pelage_stamp_query(NULL, &g_params, &a, &b));
  EXPECT(PELAGE_STATUS_NULL_PARAMETER, pelage_stamp_query(&mesh, NULL, &a, &b));
  EXPECT(PELAGE_STATUS_NULL_PARAMETER, pelage_stamp_query(&mesh, &g_params, NULL, &b));
  CHECK(untouched(&b, sizeof b));
  EXPECT(PELAGE_STATUS_NULL_PARAMETER, pelage_stamp_query(&mesh, &g_params, &a, NULL));
  CHECK(untouched(&a, sizeof a) && untouched(&b, sizeof b));

  PelageRoot *roots = malloc(g_capacity * sizeof *roots);
  size_t count;
  PelageStampInfo info;
  REQUIRE(roots);
#define STAMP_NULL(...)                                                                   \
  do {                                                                                    \
    FILL(roots, g_capacity * sizeof *roots), FILL(&count, sizeof count), FILL(&info, sizeof info); \
    EXPECT(PELAGE_STATUS_NULL_PARAMETER, pelage_stamp(__VA_ARGS__));                      \
    CHECK(untouched(roots, g_capacity * sizeof *roots));                                  \
    CHECK(untouched(&count, sizeof count));                                               \
    CHECK(untouched(&info, sizeof info));                                                 \
  } while (0)
  STAMP_NULL(NULL, &g_params, g_arena, g_arena_bytes, roots, g_capacity, &count, &info);
  STAMP_NULL(&mesh, NULL, g_arena, g_arena_bytes, roots, g_capacity, &count, &info);
  STAMP_NULL(&mesh, &g_params, NULL, g_arena_bytes, roots, g_capacity, &count, &info);
  STAMP_NULL(&mesh, &g_params, g_arena, g_arena_bytes, NULL, g_capacity, &count, &info);
  FILL(roots, g_capacity * sizeof *roots), FILL(&info, sizeof info);
  EXPECT(PELAGE_STATUS_NULL_PARAMETER,
         pelage_stamp(&mesh, &g_params, g_arena, g_arena_bytes, roots, g_capacity, NULL, &info));
  CHECK(untouched(roots, g_capacity * sizeof *roots) && untouched(&info, sizeof info));
  /* info is optional */
  EXPECT(PELAGE_STATUS_OK, pelage_stamp(&mesh, &g_params, g_arena, g_arena_bytes, roots, g_capacity, &count, NULL));
  CHECK(count == g_count);
  free(roots);

  const size_t bytes = g_count * 12;
  float *pos = malloc(bytes), *nrm = malloc(bytes);
  REQUIRE(pos && nrm);
  FILL(pos, bytes), FILL(nrm, bytes);
  bad_evaluate_(__LINE__, "evaluate(mesh NULL)", pelage_roots_evaluate(NULL, g_roots, g_count, pos, 12, nrm, 12),
                PELAGE_STATUS_NULL_PARAMETER, pos, bytes, nrm, bytes);
  bad_evaluate_(__LINE__, "evaluate(roots NULL)", pelage_roots_evaluate(&mesh, NULL, g_count, pos, 12, nrm, 12),
                PELAGE_STATUS_NULL_PARAMETER, pos, bytes, nrm, bytes);
  bad_evaluate_(__LINE__, "evaluate(positions NULL)",
                pelage_roots_evaluate(&mesh, g_roots, g_count, NULL, 12, nrm, 12), PELAGE_STATUS_NULL_PARAMETER,
                NULL, 0, nrm, bytes);
  free(pos), free(nrm);
}

static void test_bad_meshes(void) {
  const Sphere *s = &g_sphere;
  const PelageMeshDesc good = sphere_desc(s);
  PelageMeshDesc m;

  m = good, m.positions = NULL;
  BAD_MESH("positions NULL", m, PELAGE_STATUS_NULL_PARAMETER);
  m = good, m.indices = NULL;
  BAD_MESH("indices NULL", m, PELAGE_STATUS_NULL_PARAMETER);

  /* strides smaller than the element (multiples of 4, so only the size is wrong) */
  m = good, m.position_stride = 8;
  BAD_MESH("position_stride 8", m, PELAGE_STATUS_INVALID_ARGUMENT);
  m = good, m.position_stride = 0;
  BAD_MESH("position_stride 0", m, PELAGE_STATUS_INVALID_ARGUMENT);
  m = good, m.index_stride = 8;
  BAD_MESH("index_stride 8", m, PELAGE_STATUS_INVALID_ARGUMENT);
  m = good, m.uv_stride = 4;
  BAD_MESH("uv_stride 4", m, PELAGE_STATUS_INVALID_ARGUMENT);
  m = good, m.normal_stride = 8;
  BAD_MESH("normal_stride 8", m, PELAGE_STATUS_INVALID_ARGUMENT);

  /* misaligned strides and pointers (the data really is laid out that way) */
  m = good, m.positions = restride(s->p, 12, s->nv, 13, 0), m.position_stride = 13;
  BAD_MESH("position_stride 13", m, PELAGE_STATUS_MISALIGNED);
  m = good, m.positions = restride(s->p, 12, s->nv, 12, 1);
  BAD_MESH("positions at +1 byte", m, PELAGE_STATUS_MISALIGNED);
  m = good, m.indices = restride(s->t, 12, s->nt, 14, 0), m.index_stride = 14;
  BAD_MESH("index_stride 14", m, PELAGE_STATUS_MISALIGNED);
  m = good, m.indices = restride(s->t, 12, s->nt, 12, 2);
  BAD_MESH("indices at +2 bytes", m, PELAGE_STATUS_MISALIGNED);
  m = good, m.uvs = restride(s->uv, 8, s->nv, 10, 0), m.uv_stride = 10;
  BAD_MESH("uv_stride 10", m, PELAGE_STATUS_MISALIGNED);
  m = good, m.normals = restride(s->n, 12, s->nv, 13, 0), m.normal_stride = 13;
  BAD_MESH("normal_stride 13", m, PELAGE_STATUS_MISALIGNED);
  m = good, m.normals = restride(s->n, 12, s->nv, 12, 3);
  BAD_MESH("normals at +3 bytes", m, PELAGE_STATUS_MISALIGNED);

  /* sizes that overflow (nothing may be read) */
  m = good, m.vertex_count = SIZE_MAX / 12;
  BAD_MESH("vertex_count SIZE_MAX/12", m, PELAGE_STATUS_INVALID_ARGUMENT);
  m = good, m.triangle_count = SIZE_MAX / 4;
  BAD_MESH("triangle_count SIZE_MAX/4", m, PELAGE_STATUS_INVALID_ARGUMENT);

  /* non-finite values */
  float(*p)[3] = malloc(s->nv * sizeof *p);
  float(*uv)[2] = malloc(s->nv * sizeof *uv);
  float(*n)[3] = malloc(s->nv * sizeof *n);
  uint32_t(*t)[3] = malloc(s->nt * sizeof *t);
  REQUIRE(p && uv && n && t);
  memcpy(p, s->p, s->nv * sizeof *p);
  p[s->nv / 2][1] = NAN;
  m = good, m.positions = p;
  BAD_MESH("NaN position", m, PELAGE_STATUS_NON_FINITE);
  p[s->nv / 2][1] = INFINITY;
  BAD_MESH("Inf position", m, PELAGE_STATUS_NON_FINITE);
  memcpy(uv, s->uv, s->nv * sizeof *uv);
  uv[7][0] = NAN;
  m = good, m.uvs = uv;
  BAD_MESH("NaN uv", m, PELAGE_STATUS_NON_FINITE);
  memcpy(n, s->n, s->nv * sizeof *n);
  n[s->nv - 1][2] = -INFINITY;
  m = good, m.normals = n;
  BAD_MESH("-Inf normal", m, PELAGE_STATUS_NON_FINITE);

  /* out-of-range vertex indices */
  memcpy(t, s->t, s->nt * sizeof *t);
  t[s->nt / 3][2] = (uint32_t)s->nv;
  m = good, m.indices = t;
  BAD_MESH("index == vertex_count", m, PELAGE_STATUS_OUT_OF_RANGE);
  t[s->nt / 3][2] = UINT32_MAX;
  BAD_MESH("index 0xFFFFFFFF", m, PELAGE_STATUS_OUT_OF_RANGE);

  /* a padded stride is fine */
  m = good, m.positions = restride(s->p, 12, s->nv, 16, 0), m.position_stride = 16;
  {
    size_t a = 0, b = 0;
    EXPECT(PELAGE_STATUS_OK, pelage_stamp_query(&m, &g_params, &a, &b));
  }
  free(p), free(uv), free(n), free(t);
  scratch_free();
}

static void test_bad_params(void) {
  const PelageMeshDesc mesh = sphere_desc(&g_sphere);
  PelageMeshDesc no_uvs = mesh;
  no_uvs.uvs = NULL;
  PelageStampParams p;

  p = g_params, p.black_scale = 0.0f;
  BAD_PARAMS("black_scale 0", mesh, p, PELAGE_STATUS_INVALID_ARGUMENT);
  p = g_params, p.black_scale = -0.5f;
  BAD_PARAMS("black_scale -0.5", mesh, p, PELAGE_STATUS_INVALID_ARGUMENT);
  p = g_params, p.black_scale = 1.5f;
  BAD_PARAMS("black_scale 1.5", mesh, p, PELAGE_STATUS_INVALID_ARGUMENT);
  /* NaN black_scale: the enum documents NON_FINITE for "an input holds NaN or
   * infinity"; INVALID_ARGUMENT ("outside its documented domain") is accepted
   * too, and the choice is printed. */
  {
    size_t a, b;
    p = g_params, p.black_scale = NAN;
    FILL(&a, sizeof a), FILL(&b, sizeof b);
    const PelageStatus s = pelage_stamp_query(&mesh, &p, &a, &b);
    CHECK(s == PELAGE_STATUS_NON_FINITE || s == PELAGE_STATUS_INVALID_ARGUMENT);
    CHECK(pelage_last_error()[0] != '\0' && untouched(&a, sizeof a) && untouched(&b, sizeof b));
    printf("note: black_scale NaN gives %s (\"%s\")\n", status_name(s), pelage_last_error());
    BAD_PARAMS("black_scale NaN", mesh, p, s);
  }
  /* an absurd target must not panic across the boundary */
  {
    size_t a = 0, b = 0;
    p = g_params, p.target_count = UINT32_MAX;
    const PelageStatus s = pelage_stamp_query(&mesh, &p, &a, &b);
    CHECK(s != PELAGE_STATUS_PANIC);
    printf("note: target_count UINT32_MAX: pelage_stamp_query gives %s, arena %zu bytes, max_roots %zu\n",
           status_name(s), a, b);
  }
  p = g_params, p.bald_below = NAN;
  BAD_PARAMS("bald_below NaN", mesh, p, PELAGE_STATUS_NON_FINITE);
  p = g_params, p.bald_below = INFINITY;
  BAD_PARAMS("bald_below Inf", mesh, p, PELAGE_STATUS_NON_FINITE);
  p = g_params, p.density.constant = NAN;
  BAD_PARAMS("constant density NaN", mesh, p, PELAGE_STATUS_NON_FINITE);

  /* texture maps */
  static const unsigned char tex[4 * 4] = {0};
  static const float ftex[4] = {0.0f, 1.0f, 0.5f, 0.25f};
  float ftex_nan[4];
  memcpy(ftex_nan, ftex, sizeof ftex);
  ftex_nan[2] = NAN;
  PelageMap t;
  memset(&t, 0, sizeof t);
  t.kind = PELAGE_MAP_KIND_TEXTURE_U8, t.data = tex, t.width = 4, t.height = 4, t.stride = 4;
  p = g_params, p.density = t, p.density.width = 0;
  BAD_PARAMS("texture width 0", mesh, p, PELAGE_STATUS_INVALID_ARGUMENT);
  p = g_params, p.density = t, p.density.height = 0;
  BAD_PARAMS("texture height 0", mesh, p, PELAGE_STATUS_INVALID_ARGUMENT);
  p = g_params, p.density = t, p.density.width = 0, p.density.height = 0, p.density.stride = 0;
  BAD_PARAMS("texture 0 x 0", mesh, p, PELAGE_STATUS_INVALID_ARGUMENT);
  p = g_params, p.density = t, p.density.data = NULL;
  BAD_PARAMS("texture data NULL", mesh, p, PELAGE_STATUS_NULL_PARAMETER);
  p = g_params, p.density = t, p.density.stride = 3;
  BAD_PARAMS("texture stride < width", mesh, p, PELAGE_STATUS_INVALID_ARGUMENT);
  p = g_params, p.density = t, p.density.width = SIZE_MAX / 2, p.density.stride = SIZE_MAX / 2;
  BAD_PARAMS("texture size overflows", mesh, p, PELAGE_STATUS_INVALID_ARGUMENT);
  p = g_params, p.density = t;
  BAD_PARAMS("texture on a mesh without UVs", no_uvs, p, PELAGE_STATUS_INVALID_ARGUMENT);
  p = g_params, p.density = t, p.density.kind = PELAGE_MAP_KIND_TEXTURE_F32, p.density.data = ftex_nan;
  p.density.width = 2, p.density.height = 2, p.density.stride = 8;
  BAD_PARAMS("f32 texture with NaN", mesh, p, PELAGE_STATUS_NON_FINITE);
  p.density.data = ftex;
  {
    size_t a = 0, b = 0;
    EXPECT(PELAGE_STATUS_OK, pelage_stamp_query(&mesh, &p, &a, &b)); /* the same map without the NaN */
  }

  /* per-vertex maps */
  float *values = malloc(g_sphere.nv * sizeof *values);
  REQUIRE(values);
  for (size_t i = 0; i < g_sphere.nv; ++i) values[i] = 0.5f;
  PelageMap v;
  memset(&v, 0, sizeof v);
  v.kind = PELAGE_MAP_KIND_PER_VERTEX, v.data = values, v.stride = 4;
  p = g_params, p.density = v, p.density.data = NULL;
  BAD_PARAMS("per-vertex data NULL", mesh, p, PELAGE_STATUS_NULL_PARAMETER);
  p = g_params, p.density = v, p.density.stride = 0;
  BAD_PARAMS("per-vertex stride 0", mesh, p, PELAGE_STATUS_INVALID_ARGUMENT);
  p = g_params, p.density = v, p.density.stride = 6, p.density.data = restride(values, 4, g_sphere.nv, 6, 0);
  BAD_PARAMS("per-vertex stride 6", mesh, p, PELAGE_STATUS_MISALIGNED);
  p = g_params, p.density = v, p.density.data = restride(values, 4, g_sphere.nv, 4, 1);
  BAD_PARAMS("per-vertex data at +1 byte", mesh, p, PELAGE_STATUS_MISALIGNED);
  values[3] = NAN;
  p = g_params, p.density = v;
  BAD_PARAMS("per-vertex NaN", mesh, p, PELAGE_STATUS_NON_FINITE);
  values[3] = 0.5f;
  p = g_params, p.density = v, p.density.width = 0, p.density.height = 0;
  {
    size_t a = 0, b = 0;
    EXPECT(PELAGE_STATUS_OK, pelage_stamp_query(&mesh, &p, &a, &b)); /* width/height unused */
  }
  free(values);
  scratch_free();
}

static void test_capacity(void) {
  const PelageMeshDesc mesh = sphere_desc(&g_sphere);
  PelageRoot *roots = malloc(g_capacity * sizeof *roots);
  size_t count;
  PelageStampInfo info;
  REQUIRE(roots);
#define FILL_OUTPUTS() FILL(roots, g_capacity * sizeof *roots), FILL(&count, sizeof count), FILL(&info, sizeof info)

  /* arena one byte short: nothing written, not even root_count */
  FILL_OUTPUTS();
  EXPECT(PELAGE_STATUS_CAPACITY_EXCEEDED,
         pelage_stamp(&mesh, &g_params, g_arena, g_arena_bytes - 1, roots, g_capacity, &count, &info));
  CHECK(untouched(roots, g_capacity * sizeof *roots));
  CHECK(untouched(&count, sizeof count));
  CHECK(untouched(&info, sizeof info));
  /* no arena at all */
  FILL_OUTPUTS();
  EXPECT(PELAGE_STATUS_CAPACITY_EXCEEDED, pelage_stamp(&mesh, &g_params, NULL, 0, roots, g_capacity, &count, &info));
  CHECK(untouched(roots, g_capacity * sizeof *roots) && untouched(&count, sizeof count) &&
        untouched(&info, sizeof info));

  /* root buffer one short: *root_count reports the count needed; the roots stay untouched */
  FILL_OUTPUTS();
  EXPECT(PELAGE_STATUS_CAPACITY_EXCEEDED,
         pelage_stamp(&mesh, &g_params, g_arena, g_arena_bytes, roots, g_count - 1, &count, &info));
  CHECK(count == g_count);
  CHECK(untouched(roots, g_capacity * sizeof *roots));
  CHECK(untouched(&info, sizeof info));
  /* no root buffer: the count query idiom */
  FILL_OUTPUTS();
  EXPECT(PELAGE_STATUS_CAPACITY_EXCEEDED,
         pelage_stamp(&mesh, &g_params, g_arena, g_arena_bytes, NULL, 0, &count, &info));
  CHECK(count == g_count);
  CHECK(untouched(&info, sizeof info));
  /* exactly the count needed is enough */
  FILL_OUTPUTS();
  EXPECT(PELAGE_STATUS_OK, pelage_stamp(&mesh, &g_params, g_arena, g_arena_bytes, roots, g_count, &count, &info));
  CHECK(count == g_count && memcmp(roots, g_roots, g_count * sizeof *roots) == 0);

  /* both too small, and by chance arena_bytes == roots_capacity: the arena is
   * the limit, so *root_count must stay untouched (it is only written when
   * the root buffer was the limit) */
  FILL_OUTPUTS();
  EXPECT(PELAGE_STATUS_CAPACITY_EXCEEDED, pelage_stamp(&mesh, &g_params, g_arena, 64, roots, 64, &count, &info));
  if (!untouched(&count, sizeof count)) {
    fprintf(stderr, "  (arena 64 bytes, roots_capacity 64: *root_count was set to %zu, the arena bytes needed "
                    "are %zu)\n", count, g_arena_bytes);
  }
  CHECK(untouched(&count, sizeof count));
  CHECK(untouched(roots, g_capacity * sizeof *roots) && untouched(&info, sizeof info));

  /* a misaligned root buffer */
  unsigned char *raw = malloc(g_capacity * sizeof *roots + 8);
  REQUIRE(raw);
  FILL(raw, g_capacity * sizeof *roots + 8), FILL(&count, sizeof count), FILL(&info, sizeof info);
  PelageRoot *misaligned = (PelageRoot *)(void *)(raw + 2); /* never dereferenced here */
  EXPECT(PELAGE_STATUS_MISALIGNED,
         pelage_stamp(&mesh, &g_params, g_arena, g_arena_bytes, misaligned, g_capacity, &count, &info));
  CHECK(untouched(raw, g_capacity * sizeof *roots + 8) && untouched(&count, sizeof count) &&
        untouched(&info, sizeof info));
  free(raw), free(roots);
}

static void test_evaluate(void) {
  const PelageMeshDesc mesh = sphere_desc(&g_sphere);
  const size_t n = g_count, bytes = n * 16 + 16;
  unsigned char *pos = malloc(bytes), *nrm = malloc(bytes);
  PelageRoot *roots = malloc(n * sizeof *roots + 8);
  REQUIRE(pos && nrm && roots);
#define EVAL_BAD(want, r, count, pp, ps, nn, ns)                                                                  \
  do {                                                                                                            \
    FILL(pos, bytes), FILL(nrm, bytes);                                                                           \
    bad_evaluate_(__LINE__, "pelage_roots_evaluate(" #r ", " #pp ", " #ps ", " #nn ", " #ns ")",                  \
                  pelage_roots_evaluate(&mesh, r, count, pp, ps, nn, ns), want, pos, bytes, nrm, bytes);          \
  } while (0)
  EVAL_BAD(PELAGE_STATUS_INVALID_ARGUMENT, g_roots, n, pos, 8, nrm, 12);
  EVAL_BAD(PELAGE_STATUS_INVALID_ARGUMENT, g_roots, n, pos, 0, nrm, 12);
  EVAL_BAD(PELAGE_STATUS_MISALIGNED, g_roots, n, pos, 13, nrm, 12);
  EVAL_BAD(PELAGE_STATUS_MISALIGNED, g_roots, n, pos + 1, 12, nrm, 12);
  EVAL_BAD(PELAGE_STATUS_INVALID_ARGUMENT, g_roots, n, pos, 12, nrm, 8);
  EVAL_BAD(PELAGE_STATUS_MISALIGNED, g_roots, n, pos, 12, nrm, 13);
  EVAL_BAD(PELAGE_STATUS_MISALIGNED, g_roots, n, pos, 12, nrm + 2, 12);
  EVAL_BAD(PELAGE_STATUS_INVALID_ARGUMENT, g_roots, n, pos, SIZE_MAX / 8 * 4, nrm, 12); /* size overflows */

  /* misaligned roots */
  memcpy((unsigned char *)roots + 2, g_roots, n * sizeof *roots);
  EVAL_BAD(PELAGE_STATUS_MISALIGNED, (const PelageRoot *)(const void *)((unsigned char *)roots + 2), n, pos, 12,
           nrm, 12);

  /* one bad root at the end: nothing is written for the good ones either */
  memcpy(roots, g_roots, n * sizeof *roots);
  roots[n - 1].face = (uint32_t)g_sphere.nt;
  EVAL_BAD(PELAGE_STATUS_OUT_OF_RANGE, roots, n, pos, 12, nrm, 12);
  roots[n - 1].face = UINT32_MAX;
  EVAL_BAD(PELAGE_STATUS_OUT_OF_RANGE, roots, n, pos, 12, nrm, 12);
  roots[n - 1] = g_roots[n - 1];
  roots[n - 1].u = NAN;
  EVAL_BAD(PELAGE_STATUS_NON_FINITE, roots, n, pos, 12, nrm, 12);
  roots[n - 1] = g_roots[n - 1];
  roots[n / 2].v = INFINITY;
  EVAL_BAD(PELAGE_STATUS_NON_FINITE, roots, n, pos, 12, nrm, 12);
  free(pos), free(nrm), free(roots);
}

/* The last error is per thread. */
static char g_worker_first[256], g_worker_after[256];
static PelageStatus g_worker_status;
static void *worker(void *arg) {
  const PelageMeshDesc *mesh = (const PelageMeshDesc *)arg;
  PelageStampParams p = g_params;
  size_t a, b;
  snprintf(g_worker_first, sizeof g_worker_first, "%s", pelage_last_error());
  p.black_scale = 0.0f;
  g_worker_status = pelage_stamp_query(mesh, &p, &a, &b);
  snprintf(g_worker_after, sizeof g_worker_after, "%s", pelage_last_error());
  return NULL;
}

static void test_threads(void) {
  const PelageMeshDesc mesh = sphere_desc(&g_sphere);
  size_t a, b;
  char mine[256];
  EXPECT(PELAGE_STATUS_NULL_PARAMETER, pelage_stamp_query(&mesh, NULL, &a, &b));
  snprintf(mine, sizeof mine, "%s", pelage_last_error());
  pthread_t thread;
  REQUIRE(pthread_create(&thread, NULL, worker, (void *)&mesh) == 0);
  REQUIRE(pthread_join(thread, NULL) == 0);
  CHECK(g_worker_first[0] == '\0'); /* a fresh thread has no error */
  CHECK(g_worker_status == PELAGE_STATUS_INVALID_ARGUMENT && g_worker_after[0] != '\0');
  CHECK(strcmp(mine, pelage_last_error()) == 0); /* ours is unchanged */
  CHECK(strcmp(mine, g_worker_after) != 0);
  printf("last error: this thread \"%s\"; other thread \"%s\"\n", mine, g_worker_after);
}

int main(void) {
  g_sphere = sphere_new(24, 48);
  test_version_and_strings();
  test_defaults();
  test_success();
  test_maps();
  test_null_pointers();
  test_bad_meshes();
  test_bad_params();
  test_capacity();
  test_evaluate();
  test_threads();
  free(g_arena), free(g_roots);
  sphere_free(&g_sphere);
  printf("c_contract: %d checks, %d failed\n", g_checks, g_failures);
  return g_failures == 0 ? 0 : 1;
}

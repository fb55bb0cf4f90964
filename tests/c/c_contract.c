/* c_contract.c: the C API contract, from C99.
 *
 * Calls every exported function with NULL for each pointer, too-small arenas
 * and root buffers, bad and misaligned strides and pointers, NaN/Inf input,
 * out-of-range indices and bad maps, and checks for each call:
 *   - the documented PelageStatus,
 *   - a non-empty pelage_last_error() and a non-NULL pelage_status_message(),
 *   - that every output buffer (pre-filled with 0xCD canary bytes) is left
 *     untouched, except *root_count on CAPACITY_EXCEEDED from a short root
 *     buffer, which reports the count needed (documented).
 * Then the success path on a UV sphere: counts, ranges, ranks, ids, root
 * positions on their triangles, determinism, strided outputs, maps.
 *
 * Interpolation (bind, groom, frame, expand, groom handle, settle, segment
 * indices) gets the same treatment on the sphere with a few dozen guides and
 * a few hundred strands: every pointer NULL, short arenas and outputs, bad
 * strides, NaN, zero-length and zero guides, roots off the mesh, bad
 * parameters, maps and bindings; every output canary-filled and checked
 * untouched after each failure. The success path checks bindings, grooms,
 * pinned curves on their roots, counts, ids, thread-count and range
 * independence, strided output, RAW ends and the segment index buffer.
 *
 * The frame handle (PelageFrame): NULL arguments, a frame without guides, a
 * guide count or point count other than the frame's (a failed
 * pelage_frame_set_guides keeps the guides the frame had), a copied mesh,
 * re-posing, a deformed pose. Hostile inputs must never give OK with
 * non-finite output: values beyond the documented limits (mesh and guide
 * coordinates beyond 1e9, binding weights outside 0..1, groom values beyond
 * 1e6, orphan_length beyond 1e9) are refused with nothing written, and the
 * legal extremes give finite curves. Progress callbacks (bind, expand,
 * groom_expand, settle, stamp) rise to 1 on the calling thread without
 * changing the bits, and a false return cancels at once.
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
                                "VERSION_MISMATCH", "CANCELLED",   "PANIC",           "OUT_OF_MEMORY"};
  return s >= 0 && s <= 11 ? names[s] : "(unknown)";
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
  if (pelage_status_message(got) == NULL) {
    ++g_failures;
    fprintf(stderr, "%s:%d: %s: pelage_status_message(%d) is NULL\n", file, line, what, (int)got);
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

/* A PelageRun of `threads` threads and no progress callback. */
static PelageRun threads_run(uint32_t threads) {
  PelageRun run = pelage_run_defaults();
  run.thread_count = threads;
  return run;
}

/* A progress callback that records its calls and cancels at call `cancel_at`
 * (never when it is 0). */
typedef struct Progress {
  int calls, cancel_at, decreased, outside, off_thread;
  double first, last;
  pthread_t thread; /* the calling thread */
} Progress;

static Progress progress_new(int cancel_at) {
  Progress p;
  memset(&p, 0, sizeof p);
  p.cancel_at = cancel_at, p.first = -1.0, p.last = -1.0, p.thread = pthread_self();
  return p;
}

static bool on_progress(void *user_data, double fraction) {
  Progress *p = user_data;
  if (p->calls == 0) p->first = fraction;
  p->decreased |= p->calls > 0 && fraction < p->last;
  p->outside |= !(fraction >= 0.0 && fraction <= 1.0);
  p->off_thread |= !pthread_equal(p->thread, pthread_self());
  p->last = fraction;
  p->calls++;
  return p->calls != p->cancel_at;
}

/* A callback that never cancelled heard a never-decreasing share in [0, 1], ending at 1, on the
 * calling thread. */
static int progress_rose(const Progress *p) {
  return p->calls >= 2 && !p->decreased && !p->outside && !p->off_thread && p->last == 1.0;
}

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

/* Runs stamp_query, stamp and (optionally) bind_query, frame_new and
 * roots_evaluate on `mesh` with otherwise valid arguments; each must fail with
 * `want`, outputs (and *out_frame) untouched. */
static void bad_mesh_(int line, const char *name, const PelageMeshDesc *mesh, const PelageStampParams *params,
                      PelageStatus want, int evaluate) {
  char what[160];
  size_t sizes[2];
  FILL(sizes, sizeof sizes);
  snprintf(what, sizeof what, "%s: pelage_stamp_size", name);
  expect_(__FILE__, line, what, pelage_stamp_size(mesh, params, &sizes[0], &sizes[1]), want);
  if (!untouched(sizes, sizeof sizes)) ++g_failures, fprintf(stderr, "%s:%d: %s wrote its outputs\n", __FILE__, line, what);

  PelageRoot *roots = malloc(g_capacity * sizeof *roots);
  size_t count;
  PelageStampInfo info;
  REQUIRE(roots);
  FILL(roots, g_capacity * sizeof *roots), FILL(&count, sizeof count), FILL(&info, sizeof info);
  snprintf(what, sizeof what, "%s: pelage_stamp", name);
  expect_(__FILE__, line, what,
          pelage_stamp(mesh, params, (PelageArena){g_arena, g_arena_bytes}, roots, g_capacity, &count, &info), want);
  if (!untouched(roots, g_capacity * sizeof *roots) || !untouched(&count, sizeof count) ||
      !untouched(&info, sizeof info)) {
    ++g_failures, fprintf(stderr, "%s:%d: %s wrote its outputs\n", __FILE__, line, what);
  }
  free(roots);

  if (evaluate) {
    size_t bind_bytes;
    FILL(&bind_bytes, sizeof bind_bytes);
    snprintf(what, sizeof what, "%s: pelage_bind_size", name);
    expect_(__FILE__, line, what, pelage_bind_size(mesh, 100, &bind_bytes), want);
    if (!untouched(&bind_bytes, sizeof bind_bytes)) {
      ++g_failures, fprintf(stderr, "%s:%d: %s wrote its outputs\n", __FILE__, line, what);
    }

    PelageFrame frame = (PelageFrame)(void *)&g_scratch; /* a canary handle, never dereferenced */
    snprintf(what, sizeof what, "%s: pelage_frame_new", name);
    const PelageStatus made = pelage_frame_new(mesh, 100, 16, &frame);
    expect_(__FILE__, line, what, made, want);
    if (made == PELAGE_STATUS_OK) {
      pelage_frame_free(frame);
    } else if (frame != (PelageFrame)(void *)&g_scratch) {
      ++g_failures, fprintf(stderr, "%s:%d: %s wrote *out_frame\n", __FILE__, line, what);
    }

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
    const char *str = pelage_status_message(s);
    CHECK(str != NULL && str[0] != '\0');
  }
  for (int s = 1; s <= 11; ++s) { /* every defined code has its own message */
    CHECK(strcmp(pelage_status_message(s), pelage_status_message(0)) != 0);
    CHECK(strcmp(pelage_status_message(s), pelage_status_message(999)) != 0);
  }
  const int unknown[] = {999, -1, 12, INT32_MAX, INT32_MIN};
  for (size_t i = 0; i < sizeof unknown / sizeof unknown[0]; ++i) {
    const char *str = pelage_status_message(unknown[i]);
    CHECK(str != NULL && str[0] != '\0');
  }
  printf("status strings: 0 \"%s\", 5 \"%s\", 999 \"%s\"\n", pelage_status_message(0), pelage_status_message(5),
         pelage_status_message(999));
  CHECK(pelage_last_error() != NULL);
}

static void test_defaults(void) {
  const PelageStampParams d = pelage_stamp_params_defaults();
  CHECK(d.target_count == 0);
  CHECK(d.seed == 0);
  CHECK(d.density.kind == PELAGE_MAP_KIND_CONSTANT && d.density.constant == 1.0f);
  CHECK(d.black_scale == 0.5f);
  CHECK(d.bald_below == 1.0f / 512.0f);
  CHECK(d.run.progress == NULL && d.run.progress_user_data == NULL);
}

/* The reference stamp on the sphere, and the success-path invariants. */
static void test_success(void) {
  const PelageMeshDesc mesh = sphere_desc(&g_sphere);
  g_params = pelage_stamp_params_defaults();
  g_params.target_count = 3000;
  g_params.seed = 42;
  size_t arena_bytes = 0, max_roots = 0;
  EXPECT(PELAGE_STATUS_OK, pelage_stamp_size(&mesh, &g_params, &arena_bytes, &max_roots));
  REQUIRE(arena_bytes > 0 && max_roots >= g_params.target_count);
  g_arena_bytes = arena_bytes;
  g_arena = malloc(arena_bytes + 8);
  g_capacity = max_roots;
  g_roots = malloc(max_roots * sizeof *g_roots);
  REQUIRE(g_arena && g_roots);
  PelageStampInfo info;
  FILL(&info, sizeof info);
  EXPECT(PELAGE_STATUS_OK, pelage_stamp(&mesh, &g_params, (PelageArena){g_arena, arena_bytes}, g_roots, max_roots, &g_count, &info));
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
           pelage_stamp(&mesh, &g_params, (PelageArena){g_arena + offset, arena_bytes}, again, max_roots, &n, NULL));
    CHECK(n == g_count && memcmp(again, g_roots, n * sizeof *again) == 0);
    CHECK(untouched(again + n, (max_roots - n) * sizeof *again)); /* nothing past the count */
  }
  PelageStampParams other = g_params;
  other.seed = 43;
  size_t n = 0;
  EXPECT(PELAGE_STATUS_OK, pelage_stamp(&mesh, &other, (PelageArena){g_arena, arena_bytes}, again, max_roots, &n, NULL));
  CHECK(n != g_count || memcmp(again, g_roots, n * sizeof *again) != 0);
  free(again);

  /* target 0 stamps nothing */
  other = g_params;
  other.target_count = 0;
  n = 99;
  EXPECT(PELAGE_STATUS_OK, pelage_stamp(&mesh, &other, (PelageArena){g_arena, arena_bytes}, NULL, 0, &n, NULL));
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
  EXPECT(PELAGE_STATUS_OK, pelage_stamp_size(&mesh, &p, &arena_bytes, &max_roots));
  unsigned char *arena = malloc(arena_bytes);
  REQUIRE(arena && max_roots <= 2 * g_capacity);
  EXPECT(PELAGE_STATUS_OK, pelage_stamp(&mesh, &p, (PelageArena){arena, arena_bytes}, roots, max_roots, &n, NULL));
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
  EXPECT(PELAGE_STATUS_OK, pelage_stamp_size(&mesh, &p, &arena_bytes, &max_roots));
  arena = malloc(arena_bytes);
  REQUIRE(arena && max_roots <= 2 * g_capacity);
  EXPECT(PELAGE_STATUS_OK, pelage_stamp(&mesh, &p, (PelageArena){arena, arena_bytes}, roots, max_roots, &n, NULL));
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
  EXPECT(PELAGE_STATUS_NULL_PARAMETER, pelage_stamp_size(NULL, &g_params, &a, &b));
  EXPECT(PELAGE_STATUS_NULL_PARAMETER, pelage_stamp_size(&mesh, NULL, &a, &b));
  EXPECT(PELAGE_STATUS_NULL_PARAMETER, pelage_stamp_size(&mesh, &g_params, NULL, &b));
  CHECK(untouched(&b, sizeof b));
  EXPECT(PELAGE_STATUS_NULL_PARAMETER, pelage_stamp_size(&mesh, &g_params, &a, NULL));
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
  STAMP_NULL(NULL, &g_params, (PelageArena){g_arena, g_arena_bytes}, roots, g_capacity, &count, &info);
  STAMP_NULL(&mesh, NULL, (PelageArena){g_arena, g_arena_bytes}, roots, g_capacity, &count, &info);
  STAMP_NULL(&mesh, &g_params, (PelageArena){NULL, g_arena_bytes}, roots, g_capacity, &count, &info);
  STAMP_NULL(&mesh, &g_params, (PelageArena){g_arena, g_arena_bytes}, NULL, g_capacity, &count, &info);
  FILL(roots, g_capacity * sizeof *roots), FILL(&info, sizeof info);
  EXPECT(PELAGE_STATUS_NULL_PARAMETER,
         pelage_stamp(&mesh, &g_params, (PelageArena){g_arena, g_arena_bytes}, roots, g_capacity, NULL, &info));
  CHECK(untouched(roots, g_capacity * sizeof *roots) && untouched(&info, sizeof info));
  /* info is optional */
  EXPECT(PELAGE_STATUS_OK, pelage_stamp(&mesh, &g_params, (PelageArena){g_arena, g_arena_bytes}, roots, g_capacity, &count, NULL));
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
    EXPECT(PELAGE_STATUS_OK, pelage_stamp_size(&m, &g_params, &a, &b));
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
  /* NaN black_scale: any non-finite input is NON_FINITE ("an input holds NaN or infinity"), a finite one out of
   * range INVALID_ARGUMENT */
  p = g_params, p.black_scale = NAN;
  BAD_PARAMS("black_scale NaN", mesh, p, PELAGE_STATUS_NON_FINITE);
  /* an absurd target must not panic across the boundary */
  {
    size_t a = 0, b = 0;
    p = g_params, p.target_count = UINT32_MAX;
    const PelageStatus s = pelage_stamp_size(&mesh, &p, &a, &b);
    CHECK(s != PELAGE_STATUS_PANIC);
    printf("note: target_count UINT32_MAX: pelage_stamp_size gives %s, arena %zu bytes, max_roots %zu\n",
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
    EXPECT(PELAGE_STATUS_OK, pelage_stamp_size(&mesh, &p, &a, &b)); /* the same map without the NaN */
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
    EXPECT(PELAGE_STATUS_OK, pelage_stamp_size(&mesh, &p, &a, &b)); /* width/height unused */
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
         pelage_stamp(&mesh, &g_params, (PelageArena){g_arena, g_arena_bytes - 1}, roots, g_capacity, &count, &info));
  CHECK(untouched(roots, g_capacity * sizeof *roots));
  CHECK(untouched(&count, sizeof count));
  CHECK(untouched(&info, sizeof info));
  /* no arena at all */
  FILL_OUTPUTS();
  EXPECT(PELAGE_STATUS_CAPACITY_EXCEEDED, pelage_stamp(&mesh, &g_params, (PelageArena){NULL, 0}, roots, g_capacity, &count, &info));
  CHECK(untouched(roots, g_capacity * sizeof *roots) && untouched(&count, sizeof count) &&
        untouched(&info, sizeof info));

  /* root buffer one short: *root_count reports the count needed; the roots stay untouched */
  FILL_OUTPUTS();
  EXPECT(PELAGE_STATUS_CAPACITY_EXCEEDED,
         pelage_stamp(&mesh, &g_params, (PelageArena){g_arena, g_arena_bytes}, roots, g_count - 1, &count, &info));
  CHECK(count == g_count);
  CHECK(untouched(roots, g_capacity * sizeof *roots));
  CHECK(untouched(&info, sizeof info));
  /* no root buffer: the count query idiom */
  FILL_OUTPUTS();
  EXPECT(PELAGE_STATUS_CAPACITY_EXCEEDED,
         pelage_stamp(&mesh, &g_params, (PelageArena){g_arena, g_arena_bytes}, NULL, 0, &count, &info));
  CHECK(count == g_count);
  CHECK(untouched(&info, sizeof info));
  /* exactly the count needed is enough */
  FILL_OUTPUTS();
  EXPECT(PELAGE_STATUS_OK, pelage_stamp(&mesh, &g_params, (PelageArena){g_arena, g_arena_bytes}, roots, g_count, &count, &info));
  CHECK(count == g_count && memcmp(roots, g_roots, g_count * sizeof *roots) == 0);

  /* both too small, and by chance arena_bytes == roots_capacity: the arena is
   * the limit, so *root_count must stay untouched (it is only written when
   * the root buffer was the limit) */
  FILL_OUTPUTS();
  EXPECT(PELAGE_STATUS_CAPACITY_EXCEEDED, pelage_stamp(&mesh, &g_params, (PelageArena){g_arena, 64}, roots, 64, &count, &info));
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
         pelage_stamp(&mesh, &g_params, (PelageArena){g_arena, g_arena_bytes}, misaligned, g_capacity, &count, &info));
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

/* --- Interpolation: bind, groom, frame, expand, segment indices ------------------- */

#define GCVS 8          /* points per guide */
#define GLEN 0.2f       /* guide length on the unit sphere */
#define NGUIDES 60      /* guide roots wanted */
#define NSTRANDS 400    /* render strands wanted */
#define MAXSTRIDE 32    /* widest output stride tested (bytes) */

/* The interpolation fixture on the sphere: guides leaning toward -y, strands,
 * a frame posed with the guides, and every output buffer the failure cases
 * canary-fill and check. */
typedef struct Interp {
  PelageMeshDesc mesh;
  PelageRoot *guide_roots, *strands;
  size_t guide_count, strand_count;
  float (*guide_points)[3];
  PelageGuidesDesc guides;
  PelageBindParams bind_params;
  unsigned char *bind_arena;
  size_t bind_arena_bytes;
  PelageStrandBinding *bindings; /* the reference binding */
  PelageBindInfo info;
  PelageGroomMaps maps;
  PelageStrandGroom *grooms; /* the reference grooms */
  PelageExpandParams expand_params;
  PelageFrame frame; /* the rest pose, posed with the guides at expand_params.points_per_strand */
  size_t per;
  float *points; /* the reference curves, stride 16 */
  /* outputs of the failure cases */
  PelageStrandBinding *bind_out;
  PelageBindInfo info_out;
  PelageStrandGroom *groom_out;
  unsigned char *points_out; /* strand_count * per * MAXSTRIDE bytes */
  uint32_t *counts_out, *ids_out, *index_out;
  size_t sizes_out[2];
} Interp;

static Interp g_in;

/* room for per points at MAXSTRIDE, and for 67 points (points_per_strand 65, pinned) at stride 16 */
static size_t points_out_bytes(void) {
  const size_t a = g_in.strand_count * g_in.per * MAXSTRIDE, b = g_in.strand_count * 67 * 16;
  return a > b ? a : b;
}
static size_t index_out_count(void) { return g_in.strand_count * (g_in.per - 3); }
/* index_out holds one entry more, so that a misaligned pointer still has room */

static void fill_outputs(void) {
  FILL(g_in.bind_out, g_in.strand_count * sizeof *g_in.bind_out);
  FILL(&g_in.info_out, sizeof g_in.info_out);
  FILL(g_in.groom_out, g_in.strand_count * sizeof *g_in.groom_out);
  FILL(g_in.points_out, points_out_bytes());
  FILL(g_in.counts_out, g_in.strand_count * 4), FILL(g_in.ids_out, g_in.strand_count * 4);
  FILL(g_in.index_out, index_out_count() * 4 + 4);
  FILL(g_in.sizes_out, sizeof g_in.sizes_out);
}

static int outputs_untouched(void) {
  return untouched(g_in.bind_out, g_in.strand_count * sizeof *g_in.bind_out) &&
         untouched(&g_in.info_out, sizeof g_in.info_out) &&
         untouched(g_in.groom_out, g_in.strand_count * sizeof *g_in.groom_out) &&
         untouched(g_in.points_out, points_out_bytes()) && untouched(g_in.counts_out, g_in.strand_count * 4) &&
         untouched(g_in.ids_out, g_in.strand_count * 4) && untouched(g_in.index_out, index_out_count() * 4 + 4) &&
         untouched(g_in.sizes_out, sizeof g_in.sizes_out);
}

/* `call` must fail with `want` and leave every output of the fixture untouched. */
#define FAILS(want, call)                                                                   \
  do {                                                                                      \
    fill_outputs();                                                                         \
    expect_(__FILE__, __LINE__, #call, (call), (want));                                     \
    ++g_checks;                                                                             \
    if (!outputs_untouched()) {                                                             \
      ++g_failures;                                                                         \
      fprintf(stderr, "%s:%d: %s failed but wrote an output\n", __FILE__, __LINE__, #call); \
    }                                                                                       \
  } while (0)

/* The records and curve buffers of pelage_expand and pelage_groom_expand, field by field. */
static PelageStrands records(const PelageRoot *roots, const PelageStrandBinding *bindings,
                             const PelageStrandGroom *grooms, size_t count) {
  PelageStrands s;
  s.roots = roots, s.bindings = bindings, s.grooms = grooms, s.count = count;
  return s;
}
static PelageCurves curves_of(void *points, size_t stride, size_t capacity, uint32_t *counts, uint32_t *ids) {
  PelageCurves c;
  c.points = points, c.point_stride = stride, c.point_capacity = capacity;
  c.curve_counts = counts, c.curve_ids = ids;
  return c;
}
static PelageStatus expand_(PelageFrame frame, const PelageRoot *roots, const PelageStrandBinding *bindings,
                            const PelageStrandGroom *grooms, size_t count, const PelageExpandParams *params,
                            void *points, size_t stride, size_t capacity, uint32_t *counts, uint32_t *ids) {
  const PelageStrands s = records(roots, bindings, grooms, count);
  const PelageCurves c = curves_of(points, stride, capacity, counts, ids);
  return pelage_expand(frame, &s, params, &c);
}
static PelageStatus groom_expand_(PelageGroom groom, PelageFrame frame, size_t first, size_t count,
                                  const PelageExpandParams *params, void *points, size_t stride, size_t capacity,
                                  uint32_t *counts, uint32_t *ids) {
  const PelageCurves c = curves_of(points, stride, capacity, counts, ids);
  return pelage_groom_expand(groom, frame, first, count, params, &c);
}

/* The calls with the fixture's valid arguments, one argument replaced. */
#define BIND(mesh, guides, strands, count, params, arena, bytes, out, capacity) \
  pelage_bind(&(PelageRestPose){mesh, guides}, strands, count, params, (PelageArena){arena, bytes}, out, capacity, &g_in.info_out)
#define BIND_OK_ARGS                                                                          \
  &(PelageRestPose){&g_in.mesh, &g_in.guides}, g_in.strands, g_in.strand_count, &g_in.bind_params, \
      (PelageArena){g_in.bind_arena, g_in.bind_arena_bytes}, g_in.bind_out, g_in.strand_count
#define EXPAND(frame, strands, bindings, grooms, count, params, points, stride, capacity) \
  expand_(frame, strands, bindings, grooms, count, params, points, stride, capacity, g_in.counts_out, g_in.ids_out)
#define GROOM_EXPAND(groom, frame, first, count, params, points, capacity) \
  groom_expand_(groom, frame, first, count, params, points, 16, capacity, g_in.counts_out, g_in.ids_out)
#define POINTS_CAPACITY (g_in.strand_count * g_in.per)

static size_t stamp_sphere(uint32_t target, uint64_t seed, PelageRoot **out) {
  PelageStampParams p = pelage_stamp_params_defaults();
  p.target_count = target, p.seed = seed;
  size_t bytes = 0, max_roots = 0, n = 0;
  EXPECT(PELAGE_STATUS_OK, pelage_stamp_size(&g_in.mesh, &p, &bytes, &max_roots));
  void *arena = malloc(bytes);
  *out = malloc(max_roots * sizeof **out);
  REQUIRE(arena && *out);
  EXPECT(PELAGE_STATUS_OK, pelage_stamp(&g_in.mesh, &p, (PelageArena){arena, bytes}, *out, max_roots, &n, NULL));
  free(arena);
  return n;
}

/* A frame on `mesh` posed with `guides` at `points` points per strand (posed on `threads` threads). */
static PelageFrame make_frame(const PelageMeshDesc *mesh, const PelageGuidesDesc *guides, uint32_t points,
                              uint32_t threads) {
  PelageFrame frame = NULL;
  EXPECT(PELAGE_STATUS_OK, pelage_frame_new(mesh, guides->guide_count, points, &frame));
  REQUIRE(frame != NULL);
  EXPECT(PELAGE_STATUS_OK, pelage_frame_set_guides(frame, guides, threads_run(threads)));
  return frame;
}

/* Every strand expanded on `frame` with `params`: OK, and the reference bits. */
static int gives_reference(PelageFrame frame, const PelageExpandParams *params) {
  FILL(g_in.points_out, points_out_bytes());
  const PelageStatus s = expand_(frame, g_in.strands, g_in.bindings, g_in.grooms, g_in.strand_count, params,
                                 g_in.points_out, 16, POINTS_CAPACITY, NULL, NULL);
  if (s != PELAGE_STATUS_OK) fprintf(stderr, "  (expand gave %s: \"%s\")\n", status_name(s), pelage_last_error());
  return s == PELAGE_STATUS_OK && memcmp(g_in.points_out, g_in.points, POINTS_CAPACITY * 16) == 0;
}
/* The frame (still) holds the fixture's guides. */
#define SAME_AS_REFERENCE(frame) CHECK(gives_reference(frame, &g_in.expand_params))

static size_t count_non_finite(const float *v, size_t count) {
  size_t bad = 0;
  for (size_t i = 0; i < count; ++i) bad += !isfinite(v[i]);
  return bad;
}

/* The first strand with at least one guide. */
static size_t first_bound(void) {
  size_t k = 0;
  while (k < g_in.strand_count && g_in.bindings[k].count == 0) ++k;
  REQUIRE(k < g_in.strand_count);
  return k;
}

static void test_interp_defaults(void) {
  const PelageBindParams b = pelage_bind_params_defaults();
  CHECK(b.min_neighbours == 3 && b.max_neighbours == 6 && b.seed == 0);
  CHECK(b.min_normal_dot == 0.25f && b.search_factor == 2.5f && b.max_wrap_slope == 0.3f);
  CHECK(b.regions.kind == PELAGE_REGION_KIND_NONE && b.regions.data == NULL && b.run.thread_count == 1);
  CHECK(b.run.progress == NULL && b.run.progress_user_data == NULL);
  const PelageGroomMaps m = pelage_groom_maps_defaults();
  const PelageMap *all[7] = {&m.length, &m.root_width, &m.tip_width, &m.bend, &m.kink_amplitude, &m.kink_frequency,
                             &m.clump};
  for (int i = 0; i < 7; ++i) CHECK(all[i]->kind == PELAGE_MAP_KIND_CONSTANT);
  CHECK(m.length.constant == 1.0f && m.root_width.constant == 0.002f && m.tip_width.constant == 0.0005f);
  CHECK(m.bend.constant == 0.0f && m.kink_amplitude.constant == 0.0f && m.kink_frequency.constant == 3.0f);
  CHECK(m.clump.constant == 0.0f && m.seed == 0);
  const PelageExpandParams e = pelage_expand_params_defaults();
  CHECK(e.points_per_strand == 16 && e.end_points == PELAGE_END_POINTS_PINNED);
  CHECK(e.orphan_length == 0.1f && e.run.thread_count == 1);
  CHECK(e.run.progress == NULL && e.run.progress_user_data == NULL);
}

/* Guides, strands, bind, groom, frame and expand on the sphere; the success-path invariants. */
static void test_interp_success(void) {
  g_in.mesh = sphere_desc(&g_sphere);
  g_in.guide_count = stamp_sphere(NGUIDES, 5, &g_in.guide_roots);
  g_in.strand_count = stamp_sphere(NSTRANDS, 6, &g_in.strands);
  REQUIRE(g_in.guide_count > 10 && g_in.strand_count > 100);

  /* guides: leave along the normal, lean toward -y (the comb), GCVS points */
  float(*gp)[3] = malloc(g_in.guide_count * sizeof *gp), (*gn)[3] = malloc(g_in.guide_count * sizeof *gn);
  g_in.guide_points = malloc(g_in.guide_count * GCVS * sizeof *g_in.guide_points);
  REQUIRE(gp && gn && g_in.guide_points);
  EXPECT(PELAGE_STATUS_OK, pelage_roots_evaluate(&g_in.mesh, g_in.guide_roots, g_in.guide_count, gp, 12, gn, 12));
  for (size_t g = 0; g < g_in.guide_count; ++g) {
    const float *n = gn[g];
    float comb[3] = {-n[1] * n[0], -1.0f + n[1] * n[1], -n[1] * n[2]}; /* -y minus its normal part */
    for (int j = 0; j < GCVS; ++j) {
      const float t = (float)j / (GCVS - 1), lean = 0.4f * t * t;
      float *q = g_in.guide_points[g * GCVS + (size_t)j];
      for (int k = 0; k < 3; ++k) q[k] = gp[g][k] + GLEN * (t * n[k] + lean * comb[k]);
    }
  }
  free(gp), free(gn);
  memset(&g_in.guides, 0, sizeof g_in.guides);
  g_in.guides.roots = g_in.guide_roots, g_in.guides.guide_count = g_in.guide_count;
  g_in.guides.points = g_in.guide_points, g_in.guides.point_stride = 12;
  g_in.guides.point_count = g_in.guide_count * GCVS, g_in.guides.points_per_guide = GCVS;

  /* bind */
  g_in.bind_params = pelage_bind_params_defaults();
  EXPECT(PELAGE_STATUS_OK, pelage_bind_size(&g_in.mesh, g_in.guide_count, &g_in.bind_arena_bytes));
  CHECK(g_in.bind_arena_bytes > 0);
  g_in.bind_arena = malloc(g_in.bind_arena_bytes);
  g_in.bindings = malloc(g_in.strand_count * sizeof *g_in.bindings);
  g_in.bind_out = malloc(g_in.strand_count * sizeof *g_in.bind_out);
  REQUIRE(g_in.bind_arena && g_in.bindings && g_in.bind_out);
  FILL(g_in.bindings, g_in.strand_count * sizeof *g_in.bindings), FILL(&g_in.info, sizeof g_in.info);
  EXPECT(PELAGE_STATUS_OK, pelage_bind(&(PelageRestPose){&g_in.mesh, &g_in.guides}, g_in.strands, g_in.strand_count, &g_in.bind_params, (PelageArena){g_in.bind_arena, g_in.bind_arena_bytes}, g_in.bindings, g_in.strand_count, &g_in.info));
  size_t bad_binding = 0, orphans = 0, fewer = 0;
  for (size_t i = 0; i < g_in.strand_count; ++i) {
    const PelageStrandBinding *b = &g_in.bindings[i];
    if (b->count == 0) {
      orphans++, bad_binding += b->clump != 0xFFFFFFFFu;
      continue;
    }
    double sum = 0.0;
    /* fewer than min_neighbours when fewer guides are eligible */
    int ok = b->count >= 1 && b->count <= g_in.bind_params.max_neighbours;
    fewer += b->count < g_in.bind_params.min_neighbours;
    for (uint32_t k = 0; k < b->count && k < 8; ++k) {
      ok &= b->guides[k] < g_in.guide_count && b->weights[k] >= 0.0f && b->weights[k] <= 1.0f;
      sum += b->weights[k];
    }
    ok &= fabs(sum - 1.0) < 1e-4 && b->clump == b->guides[0]; /* clump: the nearest eligible guide */
    bad_binding += !ok;
  }
  printf("interp: %zu guides x %d points, %zu strands; bind arena %zu bytes; %u orphans, %zu strands with fewer "
         "than min_neighbours guides; mean guide length %.4f, spacing %.4f\n",
         g_in.guide_count, GCVS, g_in.strand_count, g_in.bind_arena_bytes, g_in.info.orphans, fewer,
         (double)g_in.info.mean_guide_length, (double)g_in.info.mean_spacing);
  CHECK(bad_binding == 0);
  CHECK(orphans == g_in.info.orphans && orphans < g_in.strand_count / 20);
  CHECK(fabs((double)g_in.info.mean_guide_length - 0.2 * 1.02) < 0.02 && g_in.info.mean_spacing > 0.0f);
  /* info is optional; the result does not depend on it */
  FILL(g_in.bind_out, g_in.strand_count * sizeof *g_in.bind_out);
  EXPECT(PELAGE_STATUS_OK, pelage_bind(BIND_OK_ARGS, NULL));
  CHECK(memcmp(g_in.bind_out, g_in.bindings, g_in.strand_count * sizeof *g_in.bind_out) == 0);
  /* nor on the thread count */
  {
    PelageBindParams bp = g_in.bind_params;
    const unsigned threads[3] = {0, 2, 7};
    for (int t = 0; t < 3; ++t) {
      bp.run.thread_count = threads[t];
      FILL(g_in.bind_out, g_in.strand_count * sizeof *g_in.bind_out);
      EXPECT(PELAGE_STATUS_OK, pelage_bind(&(PelageRestPose){&g_in.mesh, &g_in.guides}, g_in.strands, g_in.strand_count, &bp, (PelageArena){g_in.bind_arena, g_in.bind_arena_bytes}, g_in.bind_out, g_in.strand_count, NULL));
      CHECK(memcmp(g_in.bind_out, g_in.bindings, g_in.strand_count * sizeof *g_in.bind_out) == 0);
    }
  }
  /* the same guides read from float4 slots (stride 16) bind the same */
  {
    PelageGuidesDesc wide = g_in.guides;
    wide.points = restride(g_in.guide_points, 12, g_in.guide_count * GCVS, 16, 0), wide.point_stride = 16;
    FILL(g_in.bind_out, g_in.strand_count * sizeof *g_in.bind_out);
    EXPECT(PELAGE_STATUS_OK, pelage_bind(&(PelageRestPose){&g_in.mesh, &wide}, g_in.strands, g_in.strand_count, &g_in.bind_params, (PelageArena){g_in.bind_arena, g_in.bind_arena_bytes}, g_in.bind_out, g_in.strand_count, NULL));
    CHECK(memcmp(g_in.bind_out, g_in.bindings, g_in.strand_count * sizeof *g_in.bind_out) == 0);
    scratch_free();
  }
  /* no strands: nothing to do, NULL buffers are fine */
  EXPECT(PELAGE_STATUS_OK, pelage_bind(&(PelageRestPose){&g_in.mesh, &g_in.guides}, NULL, 0, &g_in.bind_params, (PelageArena){g_in.bind_arena, g_in.bind_arena_bytes}, NULL, 0, NULL));

  /* groom */
  g_in.maps = pelage_groom_maps_defaults();
  g_in.maps.kink_amplitude.constant = 0.05f, g_in.maps.clump.constant = 0.3f, g_in.maps.bend.constant = 0.1f;
  g_in.maps.seed = 9;
  g_in.grooms = malloc(g_in.strand_count * sizeof *g_in.grooms);
  g_in.groom_out = malloc(g_in.strand_count * sizeof *g_in.groom_out);
  REQUIRE(g_in.grooms && g_in.groom_out);
  EXPECT(PELAGE_STATUS_OK, pelage_groom_evaluate(&g_in.mesh, &g_in.maps, g_in.strands, g_in.strand_count,
                                                 g_in.grooms, g_in.strand_count));
  size_t bad_groom = 0;
  for (size_t i = 0; i < g_in.strand_count; ++i) {
    const PelageStrandGroom *q = &g_in.grooms[i];
    bad_groom += !(q->length == 1.0f && q->root_radius == 0.001f && q->tip_radius == 0.00025f && q->bend == 0.1f &&
                   q->kink_amplitude == 0.05f && q->kink_frequency == 3.0f && q->clump == 0.3f &&
                   fabsf(q->kink_phase[0] * q->kink_phase[0] + q->kink_phase[1] * q->kink_phase[1] - 1.0f) < 1e-5f);
  }
  CHECK(bad_groom == 0); /* widths are diameters; the groom holds radii */
  EXPECT(PELAGE_STATUS_OK, pelage_groom_evaluate(&g_in.mesh, &g_in.maps, NULL, 0, NULL, 0));

  /* expand: query, a frame posed with the guides, then pinned 16-point curves with counts and ids */
  g_in.expand_params = pelage_expand_params_defaults();
  g_in.expand_params.orphan_length = g_in.info.mean_guide_length;
  EXPECT(PELAGE_STATUS_OK, pelage_expand_size(&g_in.expand_params, &g_in.per));
  CHECK(g_in.per == 18);
  REQUIRE(g_in.per >= 4);
  const size_t per = g_in.per, n = g_in.strand_count;
  g_in.points = malloc(n * per * 16);
  g_in.points_out = malloc(points_out_bytes());
  g_in.counts_out = malloc(n * 4), g_in.ids_out = malloc(n * 4);
  g_in.index_out = malloc(index_out_count() * 4 + 4);
  REQUIRE(g_in.points && g_in.points_out && g_in.counts_out && g_in.ids_out && g_in.index_out);
  g_in.frame = NULL;
  EXPECT(PELAGE_STATUS_OK, pelage_frame_new(&g_in.mesh, g_in.guide_count, g_in.expand_params.points_per_strand,
                                            &g_in.frame));
  REQUIRE(g_in.frame != NULL);
  EXPECT(PELAGE_STATUS_OK, pelage_frame_set_guides(g_in.frame, &g_in.guides, threads_run(1)));
  FILL(g_in.points, n * per * 16), FILL(g_in.counts_out, n * 4), FILL(g_in.ids_out, n * 4);
  EXPECT(PELAGE_STATUS_OK, expand_(g_in.frame, g_in.strands, g_in.bindings, g_in.grooms, n, &g_in.expand_params,
                                   g_in.points, 16, n * per, g_in.counts_out, g_in.ids_out));
  float(*root)[3] = malloc(n * sizeof *root);
  REQUIRE(root);
  EXPECT(PELAGE_STATUS_OK, pelage_roots_evaluate(&g_in.mesh, g_in.strands, n, root, 12, NULL, 0));
  size_t non_finite = 0, negative = 0, off_root = 0, unpinned = 0, bad_count = 0, bad_id = 0;
  double worst_root = 0.0, shortest = 1e30, longest = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const float *c = g_in.points + 4 * per * i;
    non_finite += count_non_finite(c, 4 * per);
    for (size_t j = 0; j < per; ++j) negative += c[4 * j + 3] < 0.0f;
    double d = 0.0, len = 0.0;
    for (int k = 0; k < 3; ++k) {
      d += ((double)c[k] - root[i][k]) * ((double)c[k] - root[i][k]);
      len += ((double)c[4 * (per - 1) + (size_t)k] - c[k]) * ((double)c[4 * (per - 1) + (size_t)k] - c[k]);
    }
    worst_root = sqrt(d) > worst_root ? sqrt(d) : worst_root;
    off_root += !(sqrt(d) < 1e-5);
    shortest = sqrt(len) < shortest ? sqrt(len) : shortest, longest = sqrt(len) > longest ? sqrt(len) : longest;
    unpinned += memcmp(c, c + 4, 16) != 0 || memcmp(c + 4 * (per - 1), c + 4 * (per - 2), 16) != 0;
    unpinned += c[3] != g_in.grooms[i].root_radius; /* the root's radius */
    bad_count += g_in.counts_out[i] != per;
    bad_id += g_in.ids_out[i] != g_in.strands[i].id;
  }
  printf("expand: %zu curves x %zu points; max |point 0 - root| %.2e; chord %.3f .. %.3f\n", n, per, worst_root,
         shortest, longest);
  CHECK(non_finite == 0 && negative == 0);
  CHECK(off_root == 0);  /* PINNED: point 0 is the root */
  CHECK(unpinned == 0);  /* ... repeated as point 1, the tip repeated at the end */
  CHECK(bad_count == 0); /* curve_counts filled */
  CHECK(bad_id == 0);    /* curve_ids filled */
  CHECK(shortest > 0.05 && longest < 0.4);
  free(root);

  /* the bits depend neither on the thread count of the expansion nor on that of the posing, and a
   * range gives the same curves */
  {
    PelageExpandParams p = g_in.expand_params;
    const unsigned threads[3] = {0, 2, 7};
    for (int t = 0; t < 3; ++t) {
      p.run.thread_count = threads[t];
      CHECK(gives_reference(g_in.frame, &p));
      PelageFrame f = make_frame(&g_in.mesh, &g_in.guides, g_in.expand_params.points_per_strand, threads[t]);
      SAME_AS_REFERENCE(f);
      pelage_frame_free(f);
    }
    const size_t first = n / 3;
    FILL(g_in.points_out, points_out_bytes()), FILL(g_in.counts_out, n * 4), FILL(g_in.ids_out, n * 4);
    EXPECT(PELAGE_STATUS_OK, EXPAND(g_in.frame, g_in.strands + first, g_in.bindings + first, g_in.grooms + first,
                                    n - first, &g_in.expand_params, g_in.points_out, 16, (n - first) * per));
    CHECK(memcmp(g_in.points_out, g_in.points + 4 * per * first, (n - first) * per * 16) == 0);
    CHECK(untouched(g_in.points_out + (n - first) * per * 16, points_out_bytes() - (n - first) * per * 16));
    size_t wrong = 0;
    for (size_t i = 0; i < n - first; ++i) {
      wrong += g_in.counts_out[i] != per || g_in.ids_out[i] != g_in.strands[first + i].id;
    }
    CHECK(wrong == 0);
    CHECK(untouched(g_in.counts_out + (n - first), first * 4) && untouched(g_in.ids_out + (n - first), first * 4));
  }
  /* a padded stride: the same points, the padding untouched */
  {
    FILL(g_in.points_out, points_out_bytes());
    EXPECT(PELAGE_STATUS_OK, expand_(g_in.frame, g_in.strands, g_in.bindings, g_in.grooms, n, &g_in.expand_params,
                                     g_in.points_out, MAXSTRIDE, n * per, NULL, NULL));
    size_t differ = 0, padding = 0;
    for (size_t i = 0; i < n * per; ++i) {
      differ += memcmp(g_in.points_out + i * MAXSTRIDE, g_in.points + 4 * i, 16) != 0;
      padding += !untouched(g_in.points_out + i * MAXSTRIDE + 16, MAXSTRIDE - 16);
    }
    CHECK(differ == 0 && padding == 0);
  }
  /* RAW ends: 16 points per curve, the pinned curve without its repeated ends (the same frame) */
  {
    PelageExpandParams raw = g_in.expand_params;
    raw.end_points = PELAGE_END_POINTS_RAW;
    size_t raw_per = 0;
    EXPECT(PELAGE_STATUS_OK, pelage_expand_size(&raw, &raw_per));
    CHECK(raw_per == 16);
    FILL(g_in.points_out, points_out_bytes());
    EXPECT(PELAGE_STATUS_OK, expand_(g_in.frame, g_in.strands, g_in.bindings, g_in.grooms, n, &raw, g_in.points_out,
                                     16, n * raw_per, NULL, NULL));
    size_t differ = 0;
    for (size_t i = 0; i < n; ++i) {
      differ += memcmp(g_in.points_out + 16 * raw_per * i, g_in.points + 4 * (per * i + 1), 16 * raw_per) != 0;
    }
    CHECK(differ == 0);
  }
  /* no strands */
  EXPECT(PELAGE_STATUS_OK,
         expand_(g_in.frame, NULL, NULL, NULL, 0, &g_in.expand_params, NULL, 16, 0, NULL, NULL));

  /* segment indices: curve c, segment s -> c * per + s */
  FILL(g_in.index_out, index_out_count() * 4);
  EXPECT(PELAGE_STATUS_OK, pelage_curves_segment_indices(n, per, g_in.index_out, index_out_count()));
  size_t bad_index = 0;
  for (size_t k = 0; k < index_out_count(); ++k) {
    bad_index += g_in.index_out[k] != (k / (per - 3)) * per + k % (per - 3);
  }
  CHECK(bad_index == 0);
  EXPECT(PELAGE_STATUS_OK, pelage_curves_segment_indices(0, per, NULL, 0));
  {
    uint32_t four[3] = {7, 7, 7};
    EXPECT(PELAGE_STATUS_OK, pelage_curves_segment_indices(3, 4, four, 3)); /* one segment per curve */
    CHECK(four[0] == 0 && four[1] == 4 && four[2] == 8);
  }
}

/* The frame handle: bad arguments leave *out_frame untouched; a frame without guides, or posed for
 * another point count, is refused; a failed pelage_frame_set_guides keeps the guides the frame had; the
 * mesh is copied; new guides replace the old; a deformed pose moves the curves with it. */
static void test_frame(void) {
  const size_t n = g_in.strand_count, per = g_in.per, points = g_in.guide_count * GCVS;
  const PelageFrame canary = (PelageFrame)(void *)&g_in; /* never dereferenced */
  PelageFrame out = canary, f = NULL;

  /* point counts outside 2..64, no guides, and guide counts no machine holds: a status, never an
   * allocation that aborts the process */
  const uint32_t bad_points[5] = {0, 1, 65, 1000, UINT32_MAX};
  for (int i = 0; i < 5; ++i) {
    FAILS(PELAGE_STATUS_INVALID_ARGUMENT, pelage_frame_new(&g_in.mesh, g_in.guide_count, bad_points[i], &out));
  }
  FAILS(PELAGE_STATUS_INVALID_ARGUMENT, pelage_frame_new(&g_in.mesh, 0, 16, &out));
  FAILS(PELAGE_STATUS_INVALID_ARGUMENT, pelage_frame_new(&g_in.mesh, SIZE_MAX, 16, &out));
  FAILS(PELAGE_STATUS_INVALID_ARGUMENT, pelage_frame_new(&g_in.mesh, (size_t)1 << 40, 64, &out));
  CHECK(out == canary);
  /* the bounds of the point count are fine */
  const uint32_t good_points[2] = {2, 64};
  for (int i = 0; i < 2; ++i) {
    f = make_frame(&g_in.mesh, &g_in.guides, good_points[i], 1);
    PelageExpandParams p = g_in.expand_params;
    size_t pp = 0;
    p.points_per_strand = good_points[i];
    EXPECT(PELAGE_STATUS_OK, pelage_expand_size(&p, &pp));
    CHECK(pp == good_points[i] + 2u);
    FILL(g_in.points_out, points_out_bytes());
    EXPECT(PELAGE_STATUS_OK, EXPAND(f, g_in.strands, g_in.bindings, g_in.grooms, n, &p, g_in.points_out, 16, n * pp));
    CHECK(count_non_finite((const float *)(const void *)g_in.points_out, n * pp * 4) == 0);
    CHECK(memcmp(g_in.points_out, g_in.points, 16) == 0); /* the same root */
    pelage_frame_free(f);
  }
  pelage_frame_free(NULL);

  /* a frame without guides: expand and groom_expand refuse it, nothing written */
  PelageGroom groom = NULL;
  {
    const PelageStrands r = records(g_in.strands, g_in.bindings, g_in.grooms, n);
    EXPECT(PELAGE_STATUS_OK, pelage_groom_new(&r, &groom));
    REQUIRE(groom != NULL);
  }
  f = NULL;
  EXPECT(PELAGE_STATUS_OK, pelage_frame_new(&g_in.mesh, g_in.guide_count, 16, &f));
  REQUIRE(f != NULL && f != canary);
  FAILS(PELAGE_STATUS_INVALID_ARGUMENT, EXPAND(f, g_in.strands, g_in.bindings, g_in.grooms, n, &g_in.expand_params,
                                               g_in.points_out, 16, POINTS_CAPACITY));
  FAILS(PELAGE_STATUS_INVALID_ARGUMENT,
        GROOM_EXPAND(groom, f, 0, n, &g_in.expand_params, g_in.points_out, POINTS_CAPACITY));
  /* ... even with no strands to expand */
  FAILS(PELAGE_STATUS_INVALID_ARGUMENT, EXPAND(f, NULL, NULL, NULL, 0, &g_in.expand_params, NULL, 16, 0));
  /* guide counts other than the frame's are refused, and leave it without guides */
  PelageGuidesDesc fewer = g_in.guides, more = g_in.guides;
  fewer.guide_count -= 1, fewer.point_count -= GCVS;
  PelageRoot *more_roots = malloc((g_in.guide_count + 1) * sizeof *more_roots);
  float(*more_points)[3] = malloc((points + GCVS) * sizeof *more_points);
  REQUIRE(more_roots && more_points);
  memcpy(more_roots, g_in.guide_roots, g_in.guide_count * sizeof *more_roots);
  more_roots[g_in.guide_count] = g_in.guide_roots[0];
  memcpy(more_points, g_in.guide_points, points * sizeof *more_points);
  memcpy(more_points[points], g_in.guide_points[0], GCVS * sizeof *more_points);
  more.roots = more_roots, more.guide_count += 1, more.points = more_points, more.point_count += GCVS;
  FAILS(PELAGE_STATUS_INVALID_ARGUMENT, pelage_frame_set_guides(f, &fewer, threads_run(1)));
  FAILS(PELAGE_STATUS_INVALID_ARGUMENT, pelage_frame_set_guides(f, &more, threads_run(2)));
  FAILS(PELAGE_STATUS_INVALID_ARGUMENT, EXPAND(f, g_in.strands, g_in.bindings, g_in.grooms, n, &g_in.expand_params,
                                               g_in.points_out, 16, POINTS_CAPACITY));
  /* posed: the reference bits */
  EXPECT(PELAGE_STATUS_OK, pelage_frame_set_guides(f, &g_in.guides, threads_run(1)));
  SAME_AS_REFERENCE(f);
  /* a guide count other than the frame's now leaves it with the guides it had */
  FAILS(PELAGE_STATUS_INVALID_ARGUMENT, pelage_frame_set_guides(f, &fewer, threads_run(1)));
  SAME_AS_REFERENCE(f);
  FAILS(PELAGE_STATUS_INVALID_ARGUMENT, pelage_frame_set_guides(f, &more, threads_run(0)));
  SAME_AS_REFERENCE(f);
  /* new guides (a simulation's next frame) replace the old ones: longer guides, longer curves; posing
   * the old ones again gives the old bits */
  {
    float(*longer)[3] = malloc(points * sizeof *longer);
    REQUIRE(longer);
    for (size_t g = 0; g < g_in.guide_count; ++g) {
      for (int j = 0; j < GCVS; ++j) {
        for (int k = 0; k < 3; ++k) {
          const float r = g_in.guide_points[g * GCVS][k];
          longer[g * GCVS + (size_t)j][k] = r + 1.5f * (g_in.guide_points[g * GCVS + (size_t)j][k] - r);
        }
      }
    }
    PelageGuidesDesc next = g_in.guides;
    next.points = longer;
    EXPECT(PELAGE_STATUS_OK, pelage_frame_set_guides(f, &next, threads_run(2)));
    FILL(g_in.points_out, points_out_bytes());
    EXPECT(PELAGE_STATUS_OK, EXPAND(f, g_in.strands, g_in.bindings, g_in.grooms, n, &g_in.expand_params,
                                    g_in.points_out, 16, POINTS_CAPACITY));
    const float *c = (const float *)(const void *)g_in.points_out;
    double chord_ref = 0.0, chord_new = 0.0;
    for (size_t i = 0; i < n; ++i) {
      if (g_in.bindings[i].count == 0) continue;
      const float *a = g_in.points + 4 * per * i, *b = c + 4 * per * i;
      double da = 0.0, db = 0.0;
      for (int k = 0; k < 3; ++k) {
        da += ((double)a[4 * (per - 1) + (size_t)k] - a[k]) * ((double)a[4 * (per - 1) + (size_t)k] - a[k]);
        db += ((double)b[4 * (per - 1) + (size_t)k] - b[k]) * ((double)b[4 * (per - 1) + (size_t)k] - b[k]);
      }
      chord_ref += sqrt(da), chord_new += sqrt(db);
    }
    printf("frame: guides 1.5x longer: mean chord of the bound strands %.4f -> %.4f\n", chord_ref / (double)n,
           chord_new / (double)n);
    CHECK(chord_new > 1.3 * chord_ref && chord_new < 1.7 * chord_ref);
    CHECK(memcmp(c, g_in.points, 16) == 0); /* the roots do not move */
    EXPECT(PELAGE_STATUS_OK, pelage_frame_set_guides(f, &g_in.guides, threads_run(0)));
    SAME_AS_REFERENCE(f);
    free(longer);
  }
  free(more_roots), free(more_points);
  pelage_frame_free(f);

  /* points per strand: a frame posed for 12 points refuses 16-point parameters, and the 16-point frame
   * 12-point ones; 12-point parameters on the 12-point frame expand */
  {
    PelageFrame f12 = make_frame(&g_in.mesh, &g_in.guides, 12, 1);
    PelageExpandParams p12 = g_in.expand_params;
    p12.points_per_strand = 12;
    size_t per12 = 0;
    EXPECT(PELAGE_STATUS_OK, pelage_expand_size(&p12, &per12));
    CHECK(per12 == 14);
    FAILS(PELAGE_STATUS_INVALID_ARGUMENT, EXPAND(f12, g_in.strands, g_in.bindings, g_in.grooms, n,
                                                 &g_in.expand_params, g_in.points_out, 16, POINTS_CAPACITY));
    FAILS(PELAGE_STATUS_INVALID_ARGUMENT,
          GROOM_EXPAND(groom, f12, 0, n, &g_in.expand_params, g_in.points_out, POINTS_CAPACITY));
    FAILS(PELAGE_STATUS_INVALID_ARGUMENT,
          EXPAND(g_in.frame, g_in.strands, g_in.bindings, g_in.grooms, n, &p12, g_in.points_out, 16, n * per12));
    FAILS(PELAGE_STATUS_INVALID_ARGUMENT, GROOM_EXPAND(groom, g_in.frame, 0, n, &p12, g_in.points_out, n * per12));
    FILL(g_in.points_out, points_out_bytes());
    EXPECT(PELAGE_STATUS_OK,
           EXPAND(f12, g_in.strands, g_in.bindings, g_in.grooms, n, &p12, g_in.points_out, 16, n * per12));
    const float *c = (const float *)(const void *)g_in.points_out;
    size_t off_root = 0;
    for (size_t i = 0; i < n; ++i) off_root += memcmp(c + 4 * per12 * i, g_in.points + 4 * per * i, 16) != 0;
    CHECK(off_root == 0 && count_non_finite(c, n * per12 * 4) == 0);
    CHECK(untouched(g_in.points_out + n * per12 * 16, points_out_bytes() - n * per12 * 16));
    pelage_frame_free(f12);
  }

  /* the mesh is copied: the host may overwrite and free its buffers once the frame is made */
  {
    Sphere copy = sphere_new(g_sphere.rows, g_sphere.cols);
    const PelageMeshDesc m = sphere_desc(&copy);
    f = NULL;
    EXPECT(PELAGE_STATUS_OK, pelage_frame_new(&m, g_in.guide_count, 16, &f));
    REQUIRE(f != NULL);
    for (size_t v = 0; v < copy.nv; ++v) copy.p[v][0] = NAN, copy.n[v][1] = INFINITY, copy.uv[v][0] = NAN;
    memset(copy.t, 0xff, copy.nt * sizeof *copy.t);
    sphere_free(&copy); /* read after this, ASan and Valgrind object */
    EXPECT(PELAGE_STATUS_OK, pelage_frame_set_guides(f, &g_in.guides, threads_run(1)));
    SAME_AS_REFERENCE(f);
    pelage_frame_free(f);
  }
  /* ... and so are the guides: the frame keeps them resampled */
  {
    float(*copy)[3] = malloc(points * sizeof *copy);
    PelageRoot *roots = malloc(g_in.guide_count * sizeof *roots);
    REQUIRE(copy && roots);
    memcpy(copy, g_in.guide_points, points * sizeof *copy);
    memcpy(roots, g_in.guide_roots, g_in.guide_count * sizeof *roots);
    PelageGuidesDesc g = g_in.guides;
    g.points = copy, g.roots = roots;
    f = make_frame(&g_in.mesh, &g, 16, 2);
    memset(copy, 0xff, points * sizeof *copy), memset(roots, 0xff, g_in.guide_count * sizeof *roots);
    free(copy), free(roots);
    SAME_AS_REFERENCE(f);
    pelage_frame_free(f);
  }

  /* a deformed pose: the sphere scaled by 1.5 and moved, the guides with it. The curves start at the
   * strands' roots on the deformed mesh, and but for the orphans (whose length is absolute) are the
   * reference curves scaled and moved alike; the radii stay. */
  {
    const float scale = 1.5f, shift[3] = {3.0f, -2.0f, 0.5f};
    float(*dp)[3] = malloc(g_sphere.nv * sizeof *dp), (*dg)[3] = malloc(points * sizeof *dg);
    float(*root)[3] = malloc(n * sizeof *root);
    REQUIRE(dp && dg && root);
    for (size_t v = 0; v < g_sphere.nv; ++v) {
      for (int k = 0; k < 3; ++k) dp[v][k] = scale * g_sphere.p[v][k] + shift[k];
    }
    for (size_t j = 0; j < points; ++j) {
      for (int k = 0; k < 3; ++k) dg[j][k] = scale * g_in.guide_points[j][k] + shift[k];
    }
    PelageMeshDesc dm = g_in.mesh;
    dm.positions = dp;
    PelageGuidesDesc dgd = g_in.guides;
    dgd.points = dg;
    f = make_frame(&dm, &dgd, 16, 0);
    FILL(g_in.points_out, points_out_bytes()), FILL(g_in.counts_out, n * 4), FILL(g_in.ids_out, n * 4);
    EXPECT(PELAGE_STATUS_OK, EXPAND(f, g_in.strands, g_in.bindings, g_in.grooms, n, &g_in.expand_params,
                                    g_in.points_out, 16, POINTS_CAPACITY));
    EXPECT(PELAGE_STATUS_OK, pelage_roots_evaluate(&dm, g_in.strands, n, root, 12, NULL, 0));
    const float *c = (const float *)(const void *)g_in.points_out;
    double worst_root = 0.0, worst_moved = 0.0;
    size_t radius_changed = 0, bad_meta = 0;
    for (size_t i = 0; i < n; ++i) {
      const float *a = g_in.points + 4 * per * i, *b = c + 4 * per * i;
      for (int k = 0; k < 3; ++k) {
        const double d = fabs((double)b[k] - root[i][k]);
        worst_root = d > worst_root ? d : worst_root;
      }
      bad_meta += g_in.counts_out[i] != per || g_in.ids_out[i] != g_in.strands[i].id;
      for (size_t j = 0; j < per; ++j) {
        radius_changed += a[4 * j + 3] != b[4 * j + 3];
        if (g_in.bindings[i].count == 0) continue;
        for (int k = 0; k < 3; ++k) {
          const double d = fabs((double)b[4 * j + (size_t)k] - ((double)scale * a[4 * j + (size_t)k] + shift[k]));
          worst_moved = d > worst_moved ? d : worst_moved;
        }
      }
    }
    printf("frame: deformed pose (x1.5, moved): max |point 0 - root| %.2e, max |point - moved reference| %.2e\n",
           worst_root, worst_moved);
    CHECK(count_non_finite(c, n * per * 4) == 0);
    CHECK(worst_root < 1e-5 * 4);
    CHECK(worst_moved < 1e-4);
    CHECK(radius_changed == 0 && bad_meta == 0);
    pelage_frame_free(f);
    free(dp), free(dg), free(root);
  }
  pelage_groom_free(groom);
}

static void test_interp_null_pointers(void) {
  const size_t n = g_in.strand_count;
  FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_bind_size(&g_in.mesh, g_in.guide_count, NULL));
  size_t bind_bytes = 0;
  FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_bind_size(NULL, g_in.guide_count, &bind_bytes));
  CHECK(bind_bytes == 0);

  /* pelage_bind: every pointer argument, and the pointers inside the descriptors */
  PelageGuidesDesc guides = g_in.guides;
  PelageMeshDesc mesh = g_in.mesh;
  FAILS(PELAGE_STATUS_NULL_PARAMETER, BIND(NULL, &g_in.guides, g_in.strands, n, &g_in.bind_params, g_in.bind_arena,
                                           g_in.bind_arena_bytes, g_in.bind_out, n));
  FAILS(PELAGE_STATUS_NULL_PARAMETER, BIND(&g_in.mesh, NULL, g_in.strands, n, &g_in.bind_params, g_in.bind_arena,
                                           g_in.bind_arena_bytes, g_in.bind_out, n));
  FAILS(PELAGE_STATUS_NULL_PARAMETER, BIND(&g_in.mesh, &g_in.guides, NULL, n, &g_in.bind_params, g_in.bind_arena,
                                           g_in.bind_arena_bytes, g_in.bind_out, n));
  FAILS(PELAGE_STATUS_NULL_PARAMETER, BIND(&g_in.mesh, &g_in.guides, g_in.strands, n, NULL, g_in.bind_arena,
                                           g_in.bind_arena_bytes, g_in.bind_out, n));
  FAILS(PELAGE_STATUS_NULL_PARAMETER, BIND(&g_in.mesh, &g_in.guides, g_in.strands, n, &g_in.bind_params, NULL,
                                           g_in.bind_arena_bytes, g_in.bind_out, n));
  FAILS(PELAGE_STATUS_NULL_PARAMETER, BIND(&g_in.mesh, &g_in.guides, g_in.strands, n, &g_in.bind_params,
                                           g_in.bind_arena, g_in.bind_arena_bytes, NULL, n));
  guides.roots = NULL;
  FAILS(PELAGE_STATUS_NULL_PARAMETER, BIND(&g_in.mesh, &guides, g_in.strands, n, &g_in.bind_params, g_in.bind_arena,
                                           g_in.bind_arena_bytes, g_in.bind_out, n));
  guides = g_in.guides, guides.points = NULL;
  FAILS(PELAGE_STATUS_NULL_PARAMETER, BIND(&g_in.mesh, &guides, g_in.strands, n, &g_in.bind_params, g_in.bind_arena,
                                           g_in.bind_arena_bytes, g_in.bind_out, n));
  mesh.positions = NULL;
  FAILS(PELAGE_STATUS_NULL_PARAMETER, BIND(&mesh, &g_in.guides, g_in.strands, n, &g_in.bind_params, g_in.bind_arena,
                                           g_in.bind_arena_bytes, g_in.bind_out, n));

  /* pelage_groom_evaluate */
  FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_groom_evaluate(NULL, &g_in.maps, g_in.strands, n, g_in.groom_out, n));
  FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_groom_evaluate(&g_in.mesh, NULL, g_in.strands, n, g_in.groom_out, n));
  FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_groom_evaluate(&g_in.mesh, &g_in.maps, NULL, n, g_in.groom_out, n));
  FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_groom_evaluate(&g_in.mesh, &g_in.maps, g_in.strands, n, NULL, n));
  {
    PelageGroomMaps maps = g_in.maps;
    static const unsigned char tex[4] = {1, 2, 3, 4};
    maps.clump.kind = PELAGE_MAP_KIND_TEXTURE_U8, maps.clump.data = NULL;
    maps.clump.width = 2, maps.clump.height = 2, maps.clump.stride = 2;
    FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_groom_evaluate(&g_in.mesh, &maps, g_in.strands, n, g_in.groom_out, n));
    maps.clump.data = tex;
    fill_outputs();
    EXPECT(PELAGE_STATUS_OK, pelage_groom_evaluate(&g_in.mesh, &maps, g_in.strands, n, g_in.groom_out, n));
  }

  /* pelage_frame_new and pelage_frame_set_guides: every pointer argument, and the pointers inside the
   * descriptors; *out_frame untouched, the frame keeps its guides */
  {
    const PelageFrame canary = (PelageFrame)(void *)&g_in; /* never dereferenced */
    PelageFrame out = canary;
    FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_frame_new(NULL, g_in.guide_count, 16, &out));
    FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_frame_new(&g_in.mesh, g_in.guide_count, 16, NULL));
    FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_frame_new(&mesh, g_in.guide_count, 16, &out)); /* positions NULL */
    mesh = g_in.mesh, mesh.indices = NULL;
    FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_frame_new(&mesh, g_in.guide_count, 16, &out));
    CHECK(out == canary);
    FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_frame_set_guides(NULL, &g_in.guides, threads_run(1)));
    FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_frame_set_guides(g_in.frame, NULL, threads_run(1)));
    guides = g_in.guides, guides.roots = NULL;
    FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_frame_set_guides(g_in.frame, &guides, threads_run(1)));
    guides = g_in.guides, guides.points = NULL;
    FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_frame_set_guides(g_in.frame, &guides, threads_run(2)));
    SAME_AS_REFERENCE(g_in.frame);
    pelage_frame_free(NULL);
  }

  /* pelage_expand_size */
  size_t *per = &g_in.sizes_out[1];
  FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_expand_size(NULL, per));
  FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_expand_size(&g_in.expand_params, NULL));

  /* pelage_expand: every pointer argument, and the pointers inside the records and the curves
   * (curve_counts and curve_ids are optional) */
  {
    const PelageStrands r = records(g_in.strands, g_in.bindings, g_in.grooms, n);
    const PelageCurves c = curves_of(g_in.points_out, 16, POINTS_CAPACITY, g_in.counts_out, g_in.ids_out);
    FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_expand(NULL, &r, &g_in.expand_params, &c));
    FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_expand(g_in.frame, NULL, &g_in.expand_params, &c));
    FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_expand(g_in.frame, &r, NULL, &c));
    FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_expand(g_in.frame, &r, &g_in.expand_params, NULL));
  }
#define EXPAND_NULL(strands, bindings, grooms, points)                                                      \
  FAILS(PELAGE_STATUS_NULL_PARAMETER, EXPAND(g_in.frame, strands, bindings, grooms, n, &g_in.expand_params, \
                                             points, 16, POINTS_CAPACITY))
  EXPAND_NULL(NULL, g_in.bindings, g_in.grooms, g_in.points_out);
  EXPAND_NULL(g_in.strands, NULL, g_in.grooms, g_in.points_out);
  EXPAND_NULL(g_in.strands, g_in.bindings, NULL, g_in.points_out);
  EXPAND_NULL(g_in.strands, g_in.bindings, g_in.grooms, NULL);
#undef EXPAND_NULL
  /* the optional outputs may be NULL */
  FILL(g_in.points_out, points_out_bytes());
  EXPECT(PELAGE_STATUS_OK, expand_(g_in.frame, g_in.strands, g_in.bindings, g_in.grooms, n, &g_in.expand_params,
                                   g_in.points_out, 16, POINTS_CAPACITY, NULL, g_in.ids_out));
  CHECK(memcmp(g_in.points_out, g_in.points, POINTS_CAPACITY * 16) == 0);

  /* pelage_curves_segment_indices */
  FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_curves_segment_indices(n, g_in.per, NULL, index_out_count()));
}

static void test_interp_capacity(void) {
  const size_t n = g_in.strand_count;
  /* The queried arena sizes hold at any alignment (the layout adds the
   * worst-case padding), so a few bytes short can still fit: half is too small. */
  /* bind: arena half the size, no arena, bindings one short */
  FAILS(PELAGE_STATUS_CAPACITY_EXCEEDED, BIND(&g_in.mesh, &g_in.guides, g_in.strands, n, &g_in.bind_params,
                                              g_in.bind_arena, g_in.bind_arena_bytes / 2, g_in.bind_out, n));
  FAILS(PELAGE_STATUS_CAPACITY_EXCEEDED,
        BIND(&g_in.mesh, &g_in.guides, g_in.strands, n, &g_in.bind_params, NULL, 0, g_in.bind_out, n));
  FAILS(PELAGE_STATUS_CAPACITY_EXCEEDED, BIND(&g_in.mesh, &g_in.guides, g_in.strands, n, &g_in.bind_params,
                                              g_in.bind_arena, g_in.bind_arena_bytes, g_in.bind_out, n - 1));
  FAILS(PELAGE_STATUS_CAPACITY_EXCEEDED, BIND(&g_in.mesh, &g_in.guides, g_in.strands, n, &g_in.bind_params,
                                              g_in.bind_arena, g_in.bind_arena_bytes, NULL, 0));
  /* groom: one record short */
  FAILS(PELAGE_STATUS_CAPACITY_EXCEEDED,
        pelage_groom_evaluate(&g_in.mesh, &g_in.maps, g_in.strands, n, g_in.groom_out, n - 1));
  /* expand: points one short (packed and padded), no point buffer; RAW needs 2 points per curve fewer */
  FAILS(PELAGE_STATUS_CAPACITY_EXCEEDED, EXPAND(g_in.frame, g_in.strands, g_in.bindings, g_in.grooms, n,
                                                &g_in.expand_params, g_in.points_out, 16, POINTS_CAPACITY - 1));
  FAILS(PELAGE_STATUS_CAPACITY_EXCEEDED, EXPAND(g_in.frame, g_in.strands, g_in.bindings, g_in.grooms, n,
                                                &g_in.expand_params, g_in.points_out, MAXSTRIDE, POINTS_CAPACITY - 1));
  FAILS(PELAGE_STATUS_CAPACITY_EXCEEDED, EXPAND(g_in.frame, g_in.strands, g_in.bindings, g_in.grooms, n,
                                                &g_in.expand_params, NULL, 16, 0));
  {
    PelageExpandParams raw = g_in.expand_params;
    raw.end_points = PELAGE_END_POINTS_RAW;
    FAILS(PELAGE_STATUS_CAPACITY_EXCEEDED, EXPAND(g_in.frame, g_in.strands, g_in.bindings, g_in.grooms, n, &raw,
                                                  g_in.points_out, 16, n * (g_in.per - 2) - 1));
  }
  /* segment indices: one entry short */
  FAILS(PELAGE_STATUS_CAPACITY_EXCEEDED,
        pelage_curves_segment_indices(n, g_in.per, g_in.index_out, index_out_count() - 1));
  /* the bind arena size asked for is enough at any alignment, and any 4-byte aligned place in the
   * point buffer takes the curves: the same results */
  unsigned char *bind_arena = malloc(g_in.bind_arena_bytes + 3);
  REQUIRE(bind_arena);
  for (size_t offset = 0; offset < 4; ++offset) {
    fill_outputs();
    EXPECT(PELAGE_STATUS_OK, BIND(&g_in.mesh, &g_in.guides, g_in.strands, n, &g_in.bind_params, bind_arena + offset,
                                  g_in.bind_arena_bytes, g_in.bind_out, n));
    CHECK(memcmp(g_in.bind_out, g_in.bindings, n * sizeof *g_in.bind_out) == 0);
    EXPECT(PELAGE_STATUS_OK, EXPAND(g_in.frame, g_in.strands, g_in.bindings, g_in.grooms, n, &g_in.expand_params,
                                    g_in.points_out + 4 * offset, 16, POINTS_CAPACITY));
    CHECK(memcmp(g_in.points_out + 4 * offset, g_in.points, n * g_in.per * 16) == 0);
    CHECK(untouched(g_in.points_out, 4 * offset));
  }
  free(bind_arena);
}

/* pelage_bind and pelage_frame_set_guides with the guides replaced must both fail with `want`; the
 * frame keeps the guides it had. */
#define BAD_GUIDES(want, guides_ptr)                                                                                \
  do {                                                                                                              \
    FAILS(want, BIND(&g_in.mesh, guides_ptr, g_in.strands, g_in.strand_count, &g_in.bind_params, g_in.bind_arena, \
                     g_in.bind_arena_bytes, g_in.bind_out, g_in.strand_count));                                     \
    FAILS(want, pelage_frame_set_guides(g_in.frame, guides_ptr, threads_run(2)));                                               \
    SAME_AS_REFERENCE(g_in.frame);                                                                                  \
  } while (0)

static void test_interp_bad_input(void) {
  const size_t n = g_in.strand_count, points = g_in.guide_count * GCVS;
  PelageGuidesDesc g;

  /* guide buffers: strides (the data really is laid out that way), alignment, sizes */
  g = g_in.guides, g.point_stride = 8;
  BAD_GUIDES(PELAGE_STATUS_INVALID_ARGUMENT, &g);
  g = g_in.guides, g.points = restride(g_in.guide_points, 12, points, 14, 0), g.point_stride = 14;
  BAD_GUIDES(PELAGE_STATUS_MISALIGNED, &g);
  g = g_in.guides, g.points = restride(g_in.guide_points, 12, points, 12, 2);
  BAD_GUIDES(PELAGE_STATUS_MISALIGNED, &g);
  g = g_in.guides, g.roots = restride(g_in.guide_roots, sizeof(PelageRoot), g_in.guide_count, sizeof(PelageRoot), 2);
  BAD_GUIDES(PELAGE_STATUS_MISALIGNED, &g);
  g = g_in.guides, g.point_count = points - 1;
  BAD_GUIDES(PELAGE_STATUS_INVALID_ARGUMENT, &g); /* not guide_count x points_per_guide */
  g = g_in.guides, g.points_per_guide = 1, g.point_count = g_in.guide_count;
  BAD_GUIDES(PELAGE_STATUS_INVALID_ARGUMENT, &g); /* a guide needs 2 points */
  /* zero guides (for the frame also a guide count other than its own) */
  g = g_in.guides, g.roots = NULL, g.guide_count = 0, g.points = NULL, g.point_count = 0;
  BAD_GUIDES(PELAGE_STATUS_INVALID_ARGUMENT, &g);
  g = g_in.guides, g.guide_count = 0, g.point_count = 0;
  BAD_GUIDES(PELAGE_STATUS_INVALID_ARGUMENT, &g);

  /* guide contents: NaN, a zero-length guide, a root off the mesh */
  float(*copy)[3] = malloc(points * sizeof *copy);
  PelageRoot *roots = malloc(g_in.guide_count * sizeof *roots);
  REQUIRE(copy && roots);
  memcpy(copy, g_in.guide_points, points * sizeof *copy);
  copy[points - 3][1] = NAN;
  g = g_in.guides, g.points = copy;
  BAD_GUIDES(PELAGE_STATUS_NON_FINITE, &g);
  copy[points - 3][1] = INFINITY;
  BAD_GUIDES(PELAGE_STATUS_NON_FINITE, &g);
  memcpy(copy, g_in.guide_points, points * sizeof *copy);
  for (int j = 1; j < GCVS; ++j) memcpy(copy[3 * GCVS + j], copy[3 * GCVS], sizeof copy[0]);
  BAD_GUIDES(PELAGE_STATUS_INVALID_ARGUMENT, &g);
  memcpy(roots, g_in.guide_roots, g_in.guide_count * sizeof *roots);
  roots[g_in.guide_count - 1].face = (uint32_t)g_sphere.nt;
  g = g_in.guides, g.roots = roots;
  BAD_GUIDES(PELAGE_STATUS_OUT_OF_RANGE, &g);
  roots[g_in.guide_count - 1].face = UINT32_MAX;
  BAD_GUIDES(PELAGE_STATUS_OUT_OF_RANGE, &g);
  roots[g_in.guide_count - 1] = g_in.guide_roots[g_in.guide_count - 1];
  roots[1].u = NAN;
  BAD_GUIDES(PELAGE_STATUS_NON_FINITE, &g);
  free(copy), free(roots);

  /* strands: a root off the mesh or NaN fails bind, groom and expand (pelage_groom_new does not know
   * the mesh: it takes a face past this one, and pelage_groom_expand refuses it); counts that overflow */
  PelageRoot *strands = malloc(n * sizeof *strands);
  REQUIRE(strands);
  memcpy(strands, g_in.strands, n * sizeof *strands);
  strands[n - 1].face = (uint32_t)g_sphere.nt;
  for (int pass = 0; pass < 2; ++pass) {
    const PelageStatus want = pass == 0 ? PELAGE_STATUS_OUT_OF_RANGE : PELAGE_STATUS_NON_FINITE;
    FAILS(want, BIND(&g_in.mesh, &g_in.guides, strands, n, &g_in.bind_params, g_in.bind_arena, g_in.bind_arena_bytes,
                     g_in.bind_out, n));
    FAILS(want, pelage_groom_evaluate(&g_in.mesh, &g_in.maps, strands, n, g_in.groom_out, n));
    FAILS(want, EXPAND(g_in.frame, strands, g_in.bindings, g_in.grooms, n, &g_in.expand_params, g_in.points_out, 16,
                       POINTS_CAPACITY));
    {
      PelageExpandParams threads = g_in.expand_params;
      threads.run.thread_count = 3; /* checked over threads: the same verdict */
      FAILS(want, EXPAND(g_in.frame, strands, g_in.bindings, g_in.grooms, n, &threads, g_in.points_out, 16,
                         POINTS_CAPACITY));
    }
    const PelageStrands r = records(strands, g_in.bindings, g_in.grooms, n);
    PelageGroom groom = NULL;
    EXPECT(pass == 0 ? PELAGE_STATUS_OK : PELAGE_STATUS_NON_FINITE, pelage_groom_new(&r, &groom));
    if (pass == 0) {
      REQUIRE(groom != NULL);
      FAILS(PELAGE_STATUS_OUT_OF_RANGE,
            GROOM_EXPAND(groom, g_in.frame, 0, n, &g_in.expand_params, g_in.points_out, POINTS_CAPACITY));
      /* the groom as a whole is checked against the frame (documented: "the groom's faces"), so a
       * range without that strand is refused too */
      FAILS(PELAGE_STATUS_OUT_OF_RANGE,
            GROOM_EXPAND(groom, g_in.frame, 0, n - 1, &g_in.expand_params, g_in.points_out, (n - 1) * g_in.per));
      pelage_groom_free(groom);
    } else {
      CHECK(groom == NULL);
    }
    strands[n - 1] = g_in.strands[n - 1];
    strands[n / 2].v = NAN;
  }
  /* misaligned records */
  {
    const PelageRoot *r2 = restride(g_in.strands, sizeof *g_in.strands, n, sizeof *g_in.strands, 2);
    const PelageStrandBinding *b2 = restride(g_in.bindings, sizeof *g_in.bindings, n, sizeof *g_in.bindings, 2);
    const PelageStrandGroom *g2 = restride(g_in.grooms, sizeof *g_in.grooms, n, sizeof *g_in.grooms, 2);
    FAILS(PELAGE_STATUS_MISALIGNED, EXPAND(g_in.frame, r2, g_in.bindings, g_in.grooms, n, &g_in.expand_params,
                                           g_in.points_out, 16, POINTS_CAPACITY));
    FAILS(PELAGE_STATUS_MISALIGNED, EXPAND(g_in.frame, g_in.strands, b2, g_in.grooms, n, &g_in.expand_params,
                                           g_in.points_out, 16, POINTS_CAPACITY));
    FAILS(PELAGE_STATUS_MISALIGNED, EXPAND(g_in.frame, g_in.strands, g_in.bindings, g2, n, &g_in.expand_params,
                                           g_in.points_out, 16, POINTS_CAPACITY));
    PelageGroom groom = NULL;
    const PelageStrands r = records(g_in.strands, b2, g_in.grooms, n);
    EXPECT(PELAGE_STATUS_MISALIGNED, pelage_groom_new(&r, &groom));
    CHECK(groom == NULL);
  }
  free(strands);
  FAILS(PELAGE_STATUS_INVALID_ARGUMENT, BIND(&g_in.mesh, &g_in.guides, g_in.strands, SIZE_MAX / 8, &g_in.bind_params,
                                             g_in.bind_arena, g_in.bind_arena_bytes, g_in.bind_out, SIZE_MAX));
  FAILS(PELAGE_STATUS_INVALID_ARGUMENT,
        pelage_groom_evaluate(&g_in.mesh, &g_in.maps, g_in.strands, SIZE_MAX / 8, g_in.groom_out, SIZE_MAX));
  FAILS(PELAGE_STATUS_INVALID_ARGUMENT, EXPAND(g_in.frame, g_in.strands, g_in.bindings, g_in.grooms, SIZE_MAX / 8,
                                               &g_in.expand_params, g_in.points_out, 16, SIZE_MAX));
  {
    PelageGroom groom = NULL;
    const PelageStrands r = records(g_in.strands, g_in.bindings, g_in.grooms, SIZE_MAX / 8);
    EXPECT(PELAGE_STATUS_INVALID_ARGUMENT, pelage_groom_new(&r, &groom));
    CHECK(groom == NULL);
  }

  /* bind parameters */
  PelageBindParams bp;
#define BAD_BIND_PARAMS(want)                                                                                 \
  FAILS(want, BIND(&g_in.mesh, &g_in.guides, g_in.strands, n, &bp, g_in.bind_arena, g_in.bind_arena_bytes, \
                   g_in.bind_out, n))
  bp = g_in.bind_params, bp.min_neighbours = 0;
  BAD_BIND_PARAMS(PELAGE_STATUS_INVALID_ARGUMENT);
  bp = g_in.bind_params, bp.min_neighbours = 0, bp.max_neighbours = 0;
  BAD_BIND_PARAMS(PELAGE_STATUS_INVALID_ARGUMENT);
  bp = g_in.bind_params, bp.min_neighbours = 6, bp.max_neighbours = 2;
  BAD_BIND_PARAMS(PELAGE_STATUS_INVALID_ARGUMENT);
  bp = g_in.bind_params, bp.max_neighbours = 9; /* PELAGE_MAX_NEIGHBOURS is 8 (see PelageStrandBinding) */
  BAD_BIND_PARAMS(PELAGE_STATUS_INVALID_ARGUMENT);
  bp = g_in.bind_params, bp.search_factor = 0.0f;
  BAD_BIND_PARAMS(PELAGE_STATUS_INVALID_ARGUMENT);
  bp = g_in.bind_params, bp.search_factor = INFINITY;
  BAD_BIND_PARAMS(PELAGE_STATUS_NON_FINITE);
  bp = g_in.bind_params, bp.min_normal_dot = NAN;
  BAD_BIND_PARAMS(PELAGE_STATUS_NON_FINITE);
  bp = g_in.bind_params, bp.max_wrap_slope = 0.0f;
  BAD_BIND_PARAMS(PELAGE_STATUS_INVALID_ARGUMENT);
  {
    uint32_t *regions = calloc(g_sphere.nv, sizeof *regions);
    REQUIRE(regions);
    const PelageRegionMap per_vertex = {PELAGE_REGION_KIND_PER_VERTEX, regions, 0, 0, 4};
    bp = g_in.bind_params, bp.regions = per_vertex;
    bp.regions.data = restride(regions, 4, g_sphere.nv, 6, 0), bp.regions.stride = 6;
    BAD_BIND_PARAMS(PELAGE_STATUS_MISALIGNED);
    bp = g_in.bind_params, bp.regions = per_vertex, bp.regions.stride = 0;
    BAD_BIND_PARAMS(PELAGE_STATUS_INVALID_ARGUMENT);
    bp = g_in.bind_params, bp.regions = per_vertex, bp.regions.kind = 7;
    BAD_BIND_PARAMS(PELAGE_STATUS_INVALID_ARGUMENT);
    bp = g_in.bind_params, bp.regions = per_vertex, bp.regions.data = NULL;
    BAD_BIND_PARAMS(PELAGE_STATUS_NULL_PARAMETER);
    const unsigned char ids[6] = {0};
    const PelageRegionMap painted = {PELAGE_REGION_KIND_TEXTURE_U8, ids, 3, 2, 3};
    bp = g_in.bind_params, bp.regions = painted, bp.regions.width = 0;
    BAD_BIND_PARAMS(PELAGE_STATUS_INVALID_ARGUMENT);
    bp = g_in.bind_params, bp.regions = painted, bp.regions.stride = 2;
    BAD_BIND_PARAMS(PELAGE_STATUS_INVALID_ARGUMENT);
    /* one region, per vertex or painted: the same binding as none */
    const PelageRegionMap one_region[2] = {per_vertex, painted};
    for (int k = 0; k < 2; ++k) {
      bp = g_in.bind_params, bp.regions = one_region[k];
      fill_outputs();
      EXPECT(PELAGE_STATUS_OK, BIND(&g_in.mesh, &g_in.guides, g_in.strands, n, &bp, g_in.bind_arena,
                                    g_in.bind_arena_bytes, g_in.bind_out, n));
      CHECK(memcmp(g_in.bind_out, g_in.bindings, n * sizeof *g_in.bind_out) == 0);
    }
    free(regions);
  }
#undef BAD_BIND_PARAMS

  /* groom maps: zero-size texture, unknown kind, NaN, texture without UVs */
  {
    static const unsigned char tex[4] = {0, 64, 128, 255};
    PelageMap t;
    memset(&t, 0, sizeof t);
    t.kind = PELAGE_MAP_KIND_TEXTURE_U8, t.data = tex, t.width = 2, t.height = 2, t.stride = 2;
    PelageGroomMaps m;
    PelageMeshDesc no_uvs = g_in.mesh;
    no_uvs.uvs = NULL;
#define BAD_MAPS(want, mesh) FAILS(want, pelage_groom_evaluate(mesh, &m, g_in.strands, n, g_in.groom_out, n))
    m = g_in.maps, m.length = t, m.length.width = 0;
    BAD_MAPS(PELAGE_STATUS_INVALID_ARGUMENT, &g_in.mesh);
    m = g_in.maps, m.root_width = t, m.root_width.height = 0;
    BAD_MAPS(PELAGE_STATUS_INVALID_ARGUMENT, &g_in.mesh);
    m = g_in.maps, m.clump = t, m.clump.width = 0, m.clump.height = 0, m.clump.stride = 0;
    BAD_MAPS(PELAGE_STATUS_INVALID_ARGUMENT, &g_in.mesh);
    m = g_in.maps, m.kink_amplitude.kind = 77;
    BAD_MAPS(PELAGE_STATUS_INVALID_ARGUMENT, &g_in.mesh);
    m = g_in.maps, m.tip_width.kind = 4;
    BAD_MAPS(PELAGE_STATUS_INVALID_ARGUMENT, &g_in.mesh);
    m = g_in.maps, m.bend.constant = NAN;
    BAD_MAPS(PELAGE_STATUS_NON_FINITE, &g_in.mesh);
    m = g_in.maps, m.kink_frequency = t;
    BAD_MAPS(PELAGE_STATUS_INVALID_ARGUMENT, &no_uvs);
    m = g_in.maps, m.kink_frequency = t; /* the same map on a mesh with UVs */
    fill_outputs();
    EXPECT(PELAGE_STATUS_OK, pelage_groom_evaluate(&g_in.mesh, &m, g_in.strands, n, g_in.groom_out, n));
#undef BAD_MAPS
  }

  /* expansion parameters (pelage_expand_size refuses what pelage_expand refuses) and output layout */
  PelageExpandParams ep;
#define BAD_EXPAND_PARAMS(want)                                                                                    \
  do {                                                                                                             \
    FAILS(want, EXPAND(g_in.frame, g_in.strands, g_in.bindings, g_in.grooms, n, &ep, g_in.points_out, 16,         \
                       POINTS_CAPACITY));                                                                          \
    FAILS(want, pelage_expand_size(&ep, &g_in.sizes_out[1]));                                                     \
  } while (0)
  ep = g_in.expand_params, ep.end_points = 9;
  BAD_EXPAND_PARAMS(PELAGE_STATUS_INVALID_ARGUMENT);
  ep = g_in.expand_params, ep.points_per_strand = 1;
  BAD_EXPAND_PARAMS(PELAGE_STATUS_INVALID_ARGUMENT);
  ep = g_in.expand_params, ep.points_per_strand = 0;
  BAD_EXPAND_PARAMS(PELAGE_STATUS_INVALID_ARGUMENT);
  ep = g_in.expand_params, ep.points_per_strand = 65; /* points_out has room for 67 points per curve */
  FAILS(PELAGE_STATUS_INVALID_ARGUMENT, EXPAND(g_in.frame, g_in.strands, g_in.bindings, g_in.grooms, n, &ep,
                                               g_in.points_out, 16, n * 67));
  FAILS(PELAGE_STATUS_INVALID_ARGUMENT, pelage_expand_size(&ep, &g_in.sizes_out[1]));
  ep = g_in.expand_params, ep.points_per_strand = UINT32_MAX;
  BAD_EXPAND_PARAMS(PELAGE_STATUS_INVALID_ARGUMENT);
  ep = g_in.expand_params, ep.orphan_length = NAN;
  BAD_EXPAND_PARAMS(PELAGE_STATUS_NON_FINITE);
  ep = g_in.expand_params, ep.orphan_length = -1.0f;
  BAD_EXPAND_PARAMS(PELAGE_STATUS_INVALID_ARGUMENT);
  ep = g_in.expand_params, ep.orphan_length = INFINITY;
  BAD_EXPAND_PARAMS(PELAGE_STATUS_NON_FINITE);
  {
    /* with a buffer sized for the valid 18 points, the invalid count is still reported (printed) */
    ep = g_in.expand_params, ep.points_per_strand = 65;
    const PelageStatus s = EXPAND(g_in.frame, g_in.strands, g_in.bindings, g_in.grooms, n, &ep, g_in.points_out, 16,
                                  n * g_in.per);
    printf("note: pelage_expand with points_per_strand 65 and room for %zu points per curve gives %s (\"%s\")\n",
           g_in.per, status_name(s), pelage_last_error());
    CHECK(s != PELAGE_STATUS_OK);
  }
#define BAD_LAYOUT(want, points, stride)                                                                   \
  FAILS(want, EXPAND(g_in.frame, g_in.strands, g_in.bindings, g_in.grooms, n, &g_in.expand_params, points, \
                     stride, POINTS_CAPACITY))
  BAD_LAYOUT(PELAGE_STATUS_INVALID_ARGUMENT, g_in.points_out, 12);
  BAD_LAYOUT(PELAGE_STATUS_INVALID_ARGUMENT, g_in.points_out, 0);
  BAD_LAYOUT(PELAGE_STATUS_MISALIGNED, g_in.points_out, 18);
  BAD_LAYOUT(PELAGE_STATUS_MISALIGNED, g_in.points_out + 2, 16);
  BAD_LAYOUT(PELAGE_STATUS_INVALID_ARGUMENT, g_in.points_out, SIZE_MAX / 8 * 4); /* size overflows */
#undef BAD_LAYOUT
  FAILS(PELAGE_STATUS_MISALIGNED,
        expand_(g_in.frame, g_in.strands, g_in.bindings, g_in.grooms, n, &g_in.expand_params, g_in.points_out, 16,
                POINTS_CAPACITY, (uint32_t *)(void *)((unsigned char *)g_in.counts_out + 2), NULL));
  FAILS(PELAGE_STATUS_MISALIGNED,
        expand_(g_in.frame, g_in.strands, g_in.bindings, g_in.grooms, n, &g_in.expand_params, g_in.points_out, 16,
                POINTS_CAPACITY, NULL, (uint32_t *)(void *)((unsigned char *)g_in.ids_out + 1)));

  /* bindings that point past the guides */
  PelageStrandBinding *b = malloc(n * sizeof *b);
  REQUIRE(b);
#define BAD_BINDINGS(want)                                                                                   \
  FAILS(want, EXPAND(g_in.frame, g_in.strands, b, g_in.grooms, n, &g_in.expand_params, g_in.points_out, 16, \
                     POINTS_CAPACITY))
  const size_t bound = first_bound();
  memcpy(b, g_in.bindings, n * sizeof *b);
  b[bound].guides[0] = (uint32_t)g_in.guide_count;
  BAD_BINDINGS(PELAGE_STATUS_OUT_OF_RANGE);
  b[bound].guides[0] = UINT32_MAX;
  BAD_BINDINGS(PELAGE_STATUS_OUT_OF_RANGE);
  memcpy(b, g_in.bindings, n * sizeof *b);
  b[n - 1].clump = (uint32_t)g_in.guide_count;
  BAD_BINDINGS(PELAGE_STATUS_OUT_OF_RANGE);
  memcpy(b, g_in.bindings, n * sizeof *b);
  b[bound].count = 9;
  BAD_BINDINGS(PELAGE_STATUS_OUT_OF_RANGE);
  memcpy(b, g_in.bindings, n * sizeof *b);
  b[bound].count = 0xCDCDCDCDu; /* a canary-filled record */
  BAD_BINDINGS(PELAGE_STATUS_OUT_OF_RANGE);
  /* unused slots past `count` are not read */
  memcpy(b, g_in.bindings, n * sizeof *b);
  for (size_t i = 0; i < n; ++i) {
    for (uint32_t k = b[i].count; k < 8; ++k) b[i].guides[k] = UINT32_MAX, b[i].weights[k] = NAN;
  }
  fill_outputs();
  EXPECT(PELAGE_STATUS_OK, EXPAND(g_in.frame, g_in.strands, b, g_in.grooms, n, &g_in.expand_params, g_in.points_out,
                                  16, POINTS_CAPACITY));
  CHECK(memcmp(g_in.points_out, g_in.points, n * g_in.per * 16) == 0);
  {
    PelageGroom groom = NULL;
    const PelageStrands r = records(g_in.strands, b, g_in.grooms, n);
    EXPECT(PELAGE_STATUS_OK, pelage_groom_new(&r, &groom));
    fill_outputs();
    EXPECT(PELAGE_STATUS_OK,
           GROOM_EXPAND(groom, g_in.frame, 0, n, &g_in.expand_params, g_in.points_out, POINTS_CAPACITY));
    CHECK(memcmp(g_in.points_out, g_in.points, n * g_in.per * 16) == 0);
    pelage_groom_free(groom);
  }
#undef BAD_BINDINGS
  free(b);

  /* segment indices */
  FAILS(PELAGE_STATUS_INVALID_ARGUMENT, pelage_curves_segment_indices(n, 3, g_in.index_out, index_out_count()));
  FAILS(PELAGE_STATUS_INVALID_ARGUMENT, pelage_curves_segment_indices(n, 0, g_in.index_out, index_out_count()));
  FAILS(PELAGE_STATUS_INVALID_ARGUMENT, /* more points than a uint32 index addresses */
        pelage_curves_segment_indices((size_t)1 << 28, 18, g_in.index_out, SIZE_MAX));
  uint32_t *odd = (uint32_t *)(void *)((unsigned char *)g_in.index_out + 1); /* never dereferenced here */
  FAILS(PELAGE_STATUS_MISALIGNED, pelage_curves_segment_indices(n, g_in.per, odd, index_out_count()));
  scratch_free();
}

/* A copy of the sphere scaled by `scale`, with the fixture's guides scaled alike (for the legal extremes). */
typedef struct Scaled {
  float (*p)[3], (*g)[3];
  PelageMeshDesc mesh;
  PelageGuidesDesc guides;
} Scaled;
static Scaled scaled_new(float scale) {
  Scaled s;
  const size_t points = g_in.guide_count * GCVS;
  s.p = malloc(g_sphere.nv * sizeof *s.p), s.g = malloc(points * sizeof *s.g);
  REQUIRE(s.p && s.g);
  for (size_t v = 0; v < g_sphere.nv; ++v) {
    for (int k = 0; k < 3; ++k) s.p[v][k] = scale * g_sphere.p[v][k];
  }
  for (size_t j = 0; j < points; ++j) {
    for (int k = 0; k < 3; ++k) s.g[j][k] = scale * g_in.guide_points[j][k];
  }
  s.mesh = g_in.mesh, s.mesh.positions = s.p;
  s.guides = g_in.guides, s.guides.points = s.g;
  return s;
}
static void scaled_free(Scaled *s) { free(s->p), free(s->g); }

/* Hostile inputs never give OK with non-finite output: values beyond the documented limits (mesh and
 * guide coordinates beyond 1e9, binding weights outside 0..1, groom values beyond 1e6, orphan_length
 * beyond 1e9) are refused with nothing written; values at the limits give finite curves.
 * (pelage_settle: see test_settle.) */
static void test_hostile(void) {
  const Sphere *s = &g_sphere;
  const size_t n = g_in.strand_count, per = g_in.per, points = g_in.guide_count * GCVS;
  const PelageGroom canary = (PelageGroom)(void *)&g_in; /* never dereferenced */

  /* mesh values beyond 1e9: finite, but their products are not. Every call that takes a mesh refuses
   * them (BAD_MESH: stamp_query, stamp, bind_query, frame_new, roots_evaluate) */
  {
    float(*p)[3] = malloc(s->nv * sizeof *p), (*nrm)[3] = malloc(s->nv * sizeof *nrm);
    float(*uv)[2] = malloc(s->nv * sizeof *uv);
    REQUIRE(p && nrm && uv);
    PelageMeshDesc m;
    const float huge[4] = {1e30f, 3e38f, -3e38f, 2e9f};
    const char *names[4] = {"position 1e30", "position 3e38", "position -3e38", "position 2e9"};
    for (int i = 0; i < 4; ++i) {
      memcpy(p, s->p, s->nv * sizeof *p);
      p[s->nv / 3][i % 3] = huge[i];
      m = g_in.mesh, m.positions = p;
      BAD_MESH(names[i], m, PELAGE_STATUS_INVALID_ARGUMENT);
    }
    memcpy(nrm, s->n, s->nv * sizeof *nrm);
    nrm[5][0] = 1e30f;
    m = g_in.mesh, m.normals = nrm;
    BAD_MESH("normal 1e30", m, PELAGE_STATUS_INVALID_ARGUMENT);
    memcpy(uv, s->uv, s->nv * sizeof *uv);
    uv[5][1] = -3e38f;
    m = g_in.mesh, m.uvs = uv;
    BAD_MESH("uv -3e38", m, PELAGE_STATUS_INVALID_ARGUMENT);
    free(p), free(nrm), free(uv);
  }

  /* a guide point 1e30 (and 3e38) from its root: set_guides (and bind) refuse it, the frame keeps
   * the guides it had */
  {
    float(*copy)[3] = malloc(points * sizeof *copy);
    REQUIRE(copy);
    PelageGuidesDesc g = g_in.guides;
    g.points = copy;
    memcpy(copy, g_in.guide_points, points * sizeof *copy);
    copy[3 * GCVS + GCVS - 1][0] += 1e30f;
    BAD_GUIDES(PELAGE_STATUS_INVALID_ARGUMENT, &g);
    memcpy(copy, g_in.guide_points, points * sizeof *copy);
    copy[5 * GCVS + 2][2] = -3e38f;
    BAD_GUIDES(PELAGE_STATUS_INVALID_ARGUMENT, &g);
    memcpy(copy, g_in.guide_points, points * sizeof *copy);
    copy[points - 1][1] = 2e9f;
    BAD_GUIDES(PELAGE_STATUS_INVALID_ARGUMENT, &g);
    free(copy);
  }

  PelageGroom groom = NULL;
  {
    const PelageStrands r = records(g_in.strands, g_in.bindings, g_in.grooms, n);
    EXPECT(PELAGE_STATUS_OK, pelage_groom_new(&r, &groom));
    REQUIRE(groom != NULL);
  }

  /* binding weights outside 0..1 (1e30, -1) and non-finite ones: pelage_groom_new and pelage_expand
   * (on one thread or several) refuse them, nothing written */
  {
    PelageStrandBinding *b = malloc(n * sizeof *b);
    REQUIRE(b);
    const size_t bound = first_bound();
    size_t last = n - 1;
    while (g_in.bindings[last].count < 2) --last;
    const float weights[5] = {1e30f, -1.0f, 1.0001f, NAN, -INFINITY};
    const PelageStatus want[5] = {PELAGE_STATUS_INVALID_ARGUMENT, PELAGE_STATUS_INVALID_ARGUMENT,
                                  PELAGE_STATUS_INVALID_ARGUMENT, PELAGE_STATUS_NON_FINITE, PELAGE_STATUS_NON_FINITE};
    PelageExpandParams threads = g_in.expand_params;
    threads.run.thread_count = 3;
    for (int i = 0; i < 5; ++i) {
      memcpy(b, g_in.bindings, n * sizeof *b);
      b[bound].weights[0] = weights[i];
      FAILS(want[i], EXPAND(g_in.frame, g_in.strands, b, g_in.grooms, n, &g_in.expand_params, g_in.points_out, 16,
                            POINTS_CAPACITY));
      PelageGroom out = canary;
      const PelageStrands r = records(g_in.strands, b, g_in.grooms, n);
      FAILS(want[i], pelage_groom_new(&r, &out));
      CHECK(out == canary);
      /* a later slot of a strand near the end, found by a worker thread: named by its index in the whole */
      memcpy(b, g_in.bindings, n * sizeof *b);
      b[last].weights[1] = weights[i];
      FAILS(want[i], EXPAND(g_in.frame, g_in.strands, b, g_in.grooms, n, &threads, g_in.points_out, 16,
                            POINTS_CAPACITY));
      char element[64];
      snprintf(element, sizeof element, "at element %zu", last);
      CHECK(strstr(pelage_last_error(), element) != NULL);
      FAILS(want[i], pelage_groom_new(&r, &out));
      CHECK(out == canary);
    }
    /* weights in 0..1 that sum to more than 1 (within 1e-4 is fine): refused, naming the strand and the field */
    memcpy(b, g_in.bindings, n * sizeof *b);
    for (uint32_t k = 0; k < b[last].count; ++k) b[last].weights[k] = 1.0f;
    FAILS(PELAGE_STATUS_INVALID_ARGUMENT, EXPAND(g_in.frame, g_in.strands, b, g_in.grooms, n, &threads,
                                                 g_in.points_out, 16, POINTS_CAPACITY));
    {
      char field[64];
      snprintf(field, sizeof field, "bindings[%zu].weights sum to", last);
      CHECK(strstr(pelage_last_error(), field) != NULL);
      const PelageStrands r = records(g_in.strands, b, g_in.grooms, n);
      PelageGroom out = canary;
      FAILS(PELAGE_STATUS_INVALID_ARGUMENT, pelage_groom_new(&r, &out));
      CHECK(out == canary);
    }
    /* the bounds themselves are fine: weights 1 and 0 (the strand's others 0, so its weights still sum to 1) */
    memcpy(b, g_in.bindings, n * sizeof *b);
    for (uint32_t k = 0; k < b[bound].count; ++k) b[bound].weights[k] = k == 0 ? 1.0f : 0.0f;
    for (uint32_t k = 0; k < b[last].count; ++k) b[last].weights[k] = k == 0 ? 1.0f : 0.0f;
    fill_outputs();
    EXPECT(PELAGE_STATUS_OK, EXPAND(g_in.frame, g_in.strands, b, g_in.grooms, n, &g_in.expand_params,
                                    g_in.points_out, 16, POINTS_CAPACITY));
    CHECK(count_non_finite((const float *)(const void *)g_in.points_out, n * per * 4) == 0);
    free(b);
  }

  /* groom values beyond 1e6 (finite): refused by pelage_groom_new and pelage_expand */
  {
    PelageStrandGroom *gr = malloc(n * sizeof *gr);
    REQUIRE(gr);
    for (int field = 0; field < 11; ++field) {
      if (field == 9 || field == 10) continue; /* lift: bounded by pi, tested with settle */
      memcpy(gr, g_in.grooms, n * sizeof *gr);
      float *values = (float *)(void *)&gr[n / 2];
      values[field] = field % 2 ? -2e6f : 1e30f;
      if (field == 1 || field == 2) values[field] = 2e6f; /* radii: positive */
      FAILS(PELAGE_STATUS_INVALID_ARGUMENT, EXPAND(g_in.frame, g_in.strands, g_in.bindings, gr, n,
                                                   &g_in.expand_params, g_in.points_out, 16, POINTS_CAPACITY));
      PelageGroom out = canary;
      const PelageStrands r = records(g_in.strands, g_in.bindings, gr, n);
      FAILS(PELAGE_STATUS_INVALID_ARGUMENT, pelage_groom_new(&r, &out));
      CHECK(out == canary);
    }
    free(gr);
  }

  /* orphan_length beyond 1e9: pelage_expand, pelage_groom_expand and the queries refuse it */
  {
    PelageExpandParams ep = g_in.expand_params;
    const float lengths[3] = {1e30f, 2e9f, -1e30f};
    for (int i = 0; i < 3; ++i) {
      ep.orphan_length = lengths[i];
      FAILS(PELAGE_STATUS_INVALID_ARGUMENT, EXPAND(g_in.frame, g_in.strands, g_in.bindings, g_in.grooms, n, &ep,
                                                   g_in.points_out, 16, POINTS_CAPACITY));
      FAILS(PELAGE_STATUS_INVALID_ARGUMENT, GROOM_EXPAND(groom, g_in.frame, 0, n, &ep, g_in.points_out,
                                                         POINTS_CAPACITY));
      FAILS(PELAGE_STATUS_INVALID_ARGUMENT, pelage_expand_size(&ep, &g_in.sizes_out[1]));
      FAILS(PELAGE_STATUS_INVALID_ARGUMENT, pelage_settle_size(&g_in.mesh, g_in.guide_count, &ep,
                                                                &g_in.sizes_out[0]));
    }
  }

  /* the legal extremes: a sphere of radius 5e8 (its guides reach 6e8, within 1e9), every groom value
   * at 1e6 (kink phase included), orphan_length 1e9: OK, and every point finite */
  {
    Scaled big = scaled_new(5e8f);
    PelageStrandGroom *gr = malloc(n * sizeof *gr);
    REQUIRE(gr);
    for (size_t i = 0; i < n; ++i) {
      gr[i] = g_in.grooms[i];
      gr[i].length = 1e6f, gr[i].root_radius = 1e6f, gr[i].tip_radius = 1e6f, gr[i].bend = -1e6f;
      gr[i].kink_amplitude = 1e6f, gr[i].kink_frequency = 1e6f, gr[i].kink_phase[0] = 1e6f;
      gr[i].kink_phase[1] = -1e6f, gr[i].clump = 1e6f;
    }
    PelageFrame f = make_frame(&big.mesh, &big.guides, 16, 2);
    PelageExpandParams ep = g_in.expand_params;
    ep.orphan_length = 1e9f;
    const PelageEndPoints ends[2] = {PELAGE_END_POINTS_PINNED, PELAGE_END_POINTS_RAW};
    for (int e = 0; e < 2; ++e) {
      ep.end_points = (uint32_t)ends[e];
      FILL(g_in.points_out, points_out_bytes());
      const PelageStatus st = EXPAND(f, g_in.strands, g_in.bindings, gr, n, &ep, g_in.points_out, 16,
                                     POINTS_CAPACITY);
      EXPECT(PELAGE_STATUS_OK, st);
      const size_t bad = count_non_finite((const float *)(const void *)g_in.points_out, n * (per - 2u * (size_t)e) * 4);
      printf("hostile: radius 5e8, groom values 1e6, orphan_length 1e9 (%s ends): %s, %zu non-finite values\n",
             e == 0 ? "pinned" : "raw", status_name(st), bad);
      CHECK(st != PELAGE_STATUS_OK || bad == 0);
    }
    /* the same through a groom */
    PelageGroom extreme = NULL;
    const PelageStrands r = records(g_in.strands, g_in.bindings, gr, n);
    EXPECT(PELAGE_STATUS_OK, pelage_groom_new(&r, &extreme));
    ep.end_points = PELAGE_END_POINTS_PINNED;
    FILL(g_in.points_out, points_out_bytes());
    EXPECT(PELAGE_STATUS_OK, GROOM_EXPAND(extreme, f, 0, n, &ep, g_in.points_out, POINTS_CAPACITY));
    CHECK(count_non_finite((const float *)(const void *)g_in.points_out, n * per * 4) == 0);
    pelage_groom_free(extreme);
    /* values just past the limits are refused on this frame too */
    gr[n - 1].kink_frequency = 1.0001e6f;
    FAILS(PELAGE_STATUS_INVALID_ARGUMENT,
          EXPAND(f, g_in.strands, g_in.bindings, gr, n, &ep, g_in.points_out, 16, POINTS_CAPACITY));
    pelage_frame_free(f);
    free(gr);
    scaled_free(&big);
  }
  pelage_groom_free(groom);
}

/* The groom handle: records checked and copied once, then expanded per frame with the same bits as
   pelage_expand; every failure leaves the outputs (and *out_groom) untouched. */
static void test_groom_handle(void) {
  const size_t n = g_in.strand_count, per = g_in.per;
  PelageStrandGroom *grooms = malloc(n * sizeof *grooms);
  PelageStrandBinding *bindings = malloc(n * sizeof *bindings);
  PelageRoot *roots = malloc(n * sizeof *roots);
  REQUIRE(grooms && bindings && roots);
  memcpy(grooms, g_in.grooms, n * sizeof *grooms);
  memcpy(bindings, g_in.bindings, n * sizeof *bindings);
  memcpy(roots, g_in.strands, n * sizeof *roots);
  PelageGroom groom = NULL, canary = (PelageGroom)(void *)&g_in;
  PelageStrands r = records(roots, bindings, grooms, n);
  EXPECT(PELAGE_STATUS_OK, pelage_groom_new(&r, &groom));
  REQUIRE(groom != NULL);
  /* a copy: the host's arrays may change afterwards */
  memset(grooms, 0xff, n * sizeof *grooms), memset(bindings, 0xff, n * sizeof *bindings);
  memset(roots, 0xff, n * sizeof *roots);
  size_t count = 0;
  EXPECT(PELAGE_STATUS_OK, pelage_groom_strand_count(groom, &count));
  CHECK(count == n);
  const unsigned threads[3] = {1, 2, 7};
  for (int t = 0; t < 3; ++t) {
    PelageExpandParams p = g_in.expand_params;
    p.run.thread_count = threads[t];
    FILL(g_in.points_out, points_out_bytes());
    EXPECT(PELAGE_STATUS_OK, GROOM_EXPAND(groom, g_in.frame, 0, n, &p, g_in.points_out, n * per));
    CHECK(memcmp(g_in.points_out, g_in.points, n * per * 16) == 0);
  }
  /* patch by patch: each range gives its slice of the whole */
  const size_t cuts[4] = {0, n / 5, n / 2 + 3, n};
  for (int c = 0; c < 3; ++c) {
    const size_t first = cuts[c], k = cuts[c + 1] - cuts[c];
    FILL(g_in.points_out, points_out_bytes());
    EXPECT(PELAGE_STATUS_OK,
           GROOM_EXPAND(groom, g_in.frame, first, k, &g_in.expand_params, g_in.points_out, k * per));
    CHECK(memcmp(g_in.points_out, g_in.points + 4 * per * first, k * per * 16) == 0);
    CHECK(g_in.ids_out[0] == g_in.strands[first].id && g_in.counts_out[0] == per);
  }
  EXPECT(PELAGE_STATUS_OK, GROOM_EXPAND(groom, g_in.frame, n, 0, &g_in.expand_params, NULL, 0));
  /* a padded stride */
  {
    FILL(g_in.points_out, points_out_bytes());
    EXPECT(PELAGE_STATUS_OK, groom_expand_(groom, g_in.frame, 0, n, &g_in.expand_params, g_in.points_out, MAXSTRIDE,
                                           n * per, NULL, NULL));
    size_t differ = 0;
    for (size_t i = 0; i < n * per; ++i) differ += memcmp(g_in.points_out + i * MAXSTRIDE, g_in.points + 4 * i, 16) != 0;
    CHECK(differ == 0);
  }

  /* failures */
  {
    const PelageCurves c = curves_of(g_in.points_out, 16, n * per, g_in.counts_out, g_in.ids_out);
    FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_groom_expand(NULL, g_in.frame, 0, n, &g_in.expand_params, &c));
    FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_groom_expand(groom, NULL, 0, n, &g_in.expand_params, &c));
    FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_groom_expand(groom, g_in.frame, 0, n, NULL, &c));
    FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_groom_expand(groom, g_in.frame, 0, n, &g_in.expand_params, NULL));
  }
  FAILS(PELAGE_STATUS_NULL_PARAMETER, GROOM_EXPAND(groom, g_in.frame, 0, n, &g_in.expand_params, NULL, n * per));
  FAILS(PELAGE_STATUS_OUT_OF_RANGE,
        GROOM_EXPAND(groom, g_in.frame, 1, n, &g_in.expand_params, g_in.points_out, n * per));
  FAILS(PELAGE_STATUS_OUT_OF_RANGE,
        GROOM_EXPAND(groom, g_in.frame, SIZE_MAX, 2, &g_in.expand_params, g_in.points_out, n * per));
  FAILS(PELAGE_STATUS_OUT_OF_RANGE,
        GROOM_EXPAND(groom, g_in.frame, n + 1, 0, &g_in.expand_params, g_in.points_out, n * per));
  FAILS(PELAGE_STATUS_CAPACITY_EXCEEDED,
        GROOM_EXPAND(groom, g_in.frame, 0, n, &g_in.expand_params, g_in.points_out, n * per - 1));
  FAILS(PELAGE_STATUS_INVALID_ARGUMENT,
        groom_expand_(groom, g_in.frame, 0, n, &g_in.expand_params, g_in.points_out, 12, n * per, NULL, NULL));
  FAILS(PELAGE_STATUS_MISALIGNED,
        groom_expand_(groom, g_in.frame, 0, n, &g_in.expand_params, g_in.points_out + 2, 16, n * per, NULL, NULL));
  {
    PelageExpandParams ep = g_in.expand_params;
    ep.end_points = 2;
    FAILS(PELAGE_STATUS_INVALID_ARGUMENT, GROOM_EXPAND(groom, g_in.frame, 0, n, &ep, g_in.points_out, n * per));
  }
  /* a frame with fewer triangles than a root's face, or fewer guides than a binding uses */
  {
    /* every guide on guide 0's root (the lowest face), on a mesh cut just after that face */
    PelageRoot *low = malloc(g_in.guide_count * sizeof *low);
    float(*lp)[3] = malloc(g_in.guide_count * GCVS * sizeof *lp);
    REQUIRE(low && lp);
    for (size_t g = 0; g < g_in.guide_count; ++g) {
      low[g] = g_in.guide_roots[0];
      memcpy(lp[g * GCVS], g_in.guide_points[0], GCVS * sizeof *lp);
    }
    PelageMeshDesc cut = g_in.mesh;
    cut.triangle_count = (size_t)g_in.guide_roots[0].face + 1;
    size_t past = 0;
    for (size_t i = 0; i < n; ++i) past += g_in.strands[i].face >= cut.triangle_count;
    REQUIRE(past > 0);
    PelageGuidesDesc lg = g_in.guides;
    lg.roots = low, lg.points = lp;
    PelageFrame small = make_frame(&cut, &lg, 16, 1);
    FAILS(PELAGE_STATUS_OUT_OF_RANGE,
          GROOM_EXPAND(groom, small, 0, n, &g_in.expand_params, g_in.points_out, n * per));
    FAILS(PELAGE_STATUS_OUT_OF_RANGE, EXPAND(small, g_in.strands, g_in.bindings, g_in.grooms, n,
                                             &g_in.expand_params, g_in.points_out, 16, n * per));
    pelage_frame_free(small);
    free(low), free(lp);
    PelageGuidesDesc two = g_in.guides;
    two.guide_count = 2, two.point_count = 2 * (size_t)two.points_per_guide;
    PelageFrame fewer = make_frame(&g_in.mesh, &two, 16, 1);
    FAILS(PELAGE_STATUS_OUT_OF_RANGE,
          GROOM_EXPAND(groom, fewer, 0, n, &g_in.expand_params, g_in.points_out, n * per));
    FAILS(PELAGE_STATUS_OUT_OF_RANGE, EXPAND(fewer, g_in.strands, g_in.bindings, g_in.grooms, n,
                                             &g_in.expand_params, g_in.points_out, 16, n * per));
    pelage_frame_free(fewer);
  }
  size_t count_out = 77;
  EXPECT(PELAGE_STATUS_NULL_PARAMETER, pelage_groom_strand_count(NULL, &count_out));
  CHECK(count_out == 77);
  EXPECT(PELAGE_STATUS_NULL_PARAMETER, pelage_groom_strand_count(groom, NULL));

  /* bad records are refused when the groom is made, *out_groom untouched */
  memcpy(grooms, g_in.grooms, n * sizeof *grooms);
  memcpy(bindings, g_in.bindings, n * sizeof *bindings);
  memcpy(roots, g_in.strands, n * sizeof *roots);
  PelageGroom out = canary;
  EXPECT(PELAGE_STATUS_NULL_PARAMETER, pelage_groom_new(NULL, &out));
  EXPECT(PELAGE_STATUS_NULL_PARAMETER, pelage_groom_new(&r, NULL));
  r = records(NULL, bindings, grooms, n);
  EXPECT(PELAGE_STATUS_NULL_PARAMETER, pelage_groom_new(&r, &out));
  r = records(roots, NULL, grooms, n);
  EXPECT(PELAGE_STATUS_NULL_PARAMETER, pelage_groom_new(&r, &out));
  r = records(roots, bindings, NULL, n);
  EXPECT(PELAGE_STATUS_NULL_PARAMETER, pelage_groom_new(&r, &out));
  r = records(roots, bindings, grooms, n);
  grooms[n / 2].kink_amplitude = NAN;
  EXPECT(PELAGE_STATUS_NON_FINITE, pelage_groom_new(&r, &out));
  grooms[n / 2] = g_in.grooms[n / 2];
  grooms[n / 2].root_radius = -0.001f;
  EXPECT(PELAGE_STATUS_INVALID_ARGUMENT, pelage_groom_new(&r, &out));
  grooms[n / 2] = g_in.grooms[n / 2];
  grooms[n / 2].lift[0] = 3.2f; /* more than pi */
  EXPECT(PELAGE_STATUS_INVALID_ARGUMENT, pelage_groom_new(&r, &out));
  grooms[n / 2] = g_in.grooms[n / 2];
  bindings[n / 3].count = 99;
  EXPECT(PELAGE_STATUS_OUT_OF_RANGE, pelage_groom_new(&r, &out));
  bindings[n / 3] = g_in.bindings[n / 3];
  roots[n / 4].u = INFINITY;
  EXPECT(PELAGE_STATUS_NON_FINITE, pelage_groom_new(&r, &out));
  roots[n / 4] = g_in.strands[n / 4];
  CHECK(out == canary);
  /* an empty groom */
  r = records(NULL, NULL, NULL, 0);
  EXPECT(PELAGE_STATUS_OK, pelage_groom_new(&r, &out));
  CHECK(out != canary && out != NULL);
  EXPECT(PELAGE_STATUS_OK, pelage_groom_strand_count(out, &count));
  CHECK(count == 0);
  EXPECT(PELAGE_STATUS_OK, GROOM_EXPAND(out, g_in.frame, 0, 0, &g_in.expand_params, NULL, 0));
  FAILS(PELAGE_STATUS_OUT_OF_RANGE, GROOM_EXPAND(out, g_in.frame, 0, 1, &g_in.expand_params, g_in.points_out, per));
  pelage_groom_free(out);
  pelage_groom_free(groom);
  pelage_groom_free(NULL);
  free(grooms), free(bindings), free(roots);
}

/* Render-time files: patches, the groom file and the guide cache, through
 * the C API on the interpolation fixture. */
static void test_files(void) {
  const size_t n = g_in.strand_count, g = g_in.guide_count;
  const uint32_t size = 64;
  const size_t most = (n + size - 1) / size;
  uint32_t *order = malloc(n * sizeof *order);
  PelagePatch *patches = malloc(most * sizeof *patches);
  size_t patch_count = 0;
  REQUIRE(order && patches);
  EXPECT(PELAGE_STATUS_OK, pelage_patch_plan(&g_in.mesh, g_in.strands, n, size, order, patches, most, &patch_count));
  CHECK(patch_count == most && patches[0].first == 0);
  EXPECT(PELAGE_STATUS_CAPACITY_EXCEEDED,
         pelage_patch_plan(&g_in.mesh, g_in.strands, n, size, order, patches, most - 1, &patch_count));
  EXPECT(PELAGE_STATUS_INVALID_ARGUMENT,
         pelage_patch_plan(&g_in.mesh, g_in.strands, n, 0, order, patches, most, &patch_count));
  EXPECT(PELAGE_STATUS_NULL_PARAMETER,
         pelage_patch_plan(&g_in.mesh, g_in.strands, n, size, NULL, patches, most, &patch_count));
  /* the strands in patch order */
  PelageRoot *roots = malloc(n * sizeof *roots);
  PelageStrandBinding *bindings = malloc(n * sizeof *bindings);
  PelageStrandGroom *grooms = malloc(n * sizeof *grooms);
  REQUIRE(roots && bindings && grooms);
  for (size_t k = 0; k < n; ++k)
    roots[k] = g_in.strands[order[k]], bindings[k] = g_in.bindings[order[k]], grooms[k] = g_in.grooms[order[k]];
  const PelageStrands strands = records(roots, bindings, grooms, n);

  /* the groom file: sized, written, read back */
  PelageGroomFileDesc desc = {g_in.frame, g_in.guide_roots, strands, patches, patch_count};
  size_t bytes = 0, written = 0;
  EXPECT(PELAGE_STATUS_CAPACITY_EXCEEDED, pelage_groom_file_write(&desc, NULL, 0, &bytes));
  CHECK(bytes > 0);
  unsigned char *file = malloc(bytes);
  REQUIRE(file);
  EXPECT(PELAGE_STATUS_OK, pelage_groom_file_write(&desc, file, bytes, &written));
  CHECK(written == bytes);
  PelageGroomFileInfo info;
  EXPECT(PELAGE_STATUS_OK, pelage_groom_file_info(file, bytes, &info));
  const uint32_t pts = g_in.expand_params.points_per_strand;
  CHECK(info.guide_count == g && info.points_per_guide == pts && info.strand_count == n);
  CHECK(info.patch_count == patch_count);
  PelageRoot *guide_roots = malloc(g * sizeof *guide_roots);
  float *guide_points = malloc(g * pts * 3 * sizeof *guide_points);
  PelageRoot *roots2 = malloc(n * sizeof *roots2);
  PelageStrandBinding *bindings2 = malloc(n * sizeof *bindings2);
  PelageStrandGroom *grooms2 = malloc(n * sizeof *grooms2);
  PelagePatch *patches2 = malloc(most * sizeof *patches2);
  REQUIRE(guide_roots && guide_points && roots2 && bindings2 && grooms2 && patches2);
  PelageGroomFileBuffers out = {guide_roots, guide_points, g, roots2, bindings2, grooms2, n, patches2, most};
  /* damaged files: refused, nothing written */
  FILL(roots2, n * sizeof *roots2);
  file[bytes / 2] ^= 0x20;
  EXPECT(PELAGE_STATUS_CORRUPT_DATA, pelage_groom_file_read(file, bytes, &out));
  file[bytes / 2] ^= 0x20;
  EXPECT(PELAGE_STATUS_CORRUPT_DATA, pelage_groom_file_read(file, bytes - 1, &out));
  file[0] ^= 1;
  EXPECT(PELAGE_STATUS_VERSION_MISMATCH, pelage_groom_file_read(file, bytes, &out));
  file[0] ^= 1;
  out.strand_capacity = n - 1;
  EXPECT(PELAGE_STATUS_CAPACITY_EXCEEDED, pelage_groom_file_read(file, bytes, &out));
  out.strand_capacity = n;
  CHECK(untouched(roots2, n * sizeof *roots2));
  EXPECT(PELAGE_STATUS_NULL_PARAMETER, pelage_groom_file_read(NULL, bytes, &out));
  EXPECT(PELAGE_STATUS_OK, pelage_groom_file_read(file, bytes, &out));
  CHECK(memcmp(roots2, roots, n * sizeof *roots) == 0 && memcmp(bindings2, bindings, n * sizeof *bindings) == 0);
  CHECK(memcmp(grooms2, grooms, n * sizeof *grooms) == 0 && memcmp(patches2, patches, patch_count * sizeof *patches) == 0);
  CHECK(memcmp(guide_roots, g_in.guide_roots, g * sizeof *guide_roots) == 0);

  /* the guide cache, exact: a frame decoded from it expands to the same bits */
  const PelageGuideSet set = {guide_roots, guide_points, g, pts, info.id};
  size_t cache_bytes = 0;
  /* quantized may need more room than exact (a raw guide has a tag) */
  EXPECT(PELAGE_STATUS_OK, pelage_guide_cache_size(g, pts, 1, 0, &cache_bytes));
  unsigned char *cache = malloc(cache_bytes);
  REQUIRE(cache);
  EXPECT(PELAGE_STATUS_OK, pelage_guide_cache_write(&set, &g_in.frame, 1, 1, threads_run(1), cache, cache_bytes, &written));
  PelageGuideCacheInfo cinfo;
  EXPECT(PELAGE_STATUS_OK, pelage_guide_cache_info(cache, written, &cinfo));
  CHECK(cinfo.guide_count == g && cinfo.sample_count == 1 && cinfo.exact == 1 && cinfo.groom_id == info.id);
  PelageFrame decoded = NULL;
  EXPECT(PELAGE_STATUS_OK, pelage_frame_new(&g_in.mesh, g, pts, &decoded));
  REQUIRE(decoded != NULL);
  PelageGuideSet other = set;
  other.groom_id ^= 1;
  EXPECT(PELAGE_STATUS_INVALID_ARGUMENT, pelage_guide_cache_read(cache, written, &other, 0, decoded, threads_run(1)));
  EXPECT(PELAGE_STATUS_INVALID_ARGUMENT, pelage_guide_cache_read(cache, written, &set, 1, decoded, threads_run(1)));
  cache[written - 1] ^= 0x40;
  EXPECT(PELAGE_STATUS_CORRUPT_DATA, pelage_guide_cache_read(cache, written, &set, 0, decoded, threads_run(1)));
  cache[written - 1] ^= 0x40;
  EXPECT(PELAGE_STATUS_NULL_PARAMETER, pelage_guide_cache_read(cache, written, NULL, 0, decoded, threads_run(1)));
  EXPECT(PELAGE_STATUS_OK, pelage_guide_cache_read(cache, written, &set, 0, decoded, threads_run(1)));
  SAME_AS_REFERENCE(decoded);
  /* any thread count, the same bits */
  EXPECT(PELAGE_STATUS_OK, pelage_guide_cache_read(cache, written, &set, 0, decoded, threads_run(3)));
  SAME_AS_REFERENCE(decoded);
  /* quantized: smaller, and within the bound */
  size_t quantized = 0;
  EXPECT(PELAGE_STATUS_OK, pelage_guide_cache_write(&set, &g_in.frame, 1, 0, threads_run(1), cache, cache_bytes, &quantized));
  CHECK(quantized < written / 2);
  EXPECT(PELAGE_STATUS_OK, pelage_guide_cache_read(cache, quantized, &set, 0, decoded, threads_run(1)));
  EXPECT(PELAGE_STATUS_NULL_PARAMETER, pelage_guide_cache_write(&set, NULL, 1, 0, threads_run(1), cache, cache_bytes, &quantized));
  {
    /* encode and decode hear their progress, and a false return cancels them */
    unsigned char *again = malloc(cache_bytes);
    REQUIRE(again);
    Progress seen = progress_new(0), stop = progress_new(1);
    PelageRun heard = threads_run(2);
    heard.progress = on_progress, heard.progress_user_data = &seen;
    size_t same = 0;
    EXPECT(PELAGE_STATUS_OK, pelage_guide_cache_write(&set, &g_in.frame, 1, 0, heard, again, cache_bytes, &same));
    CHECK(same == quantized && memcmp(again, cache, same) == 0 && progress_rose(&seen));
    heard.progress_user_data = &stop;
    EXPECT(PELAGE_STATUS_CANCELLED, pelage_guide_cache_write(&set, &g_in.frame, 1, 0, heard, again, cache_bytes, &same));
    CHECK(stop.calls == 1);
    seen = progress_new(0), heard.progress_user_data = &seen;
    EXPECT(PELAGE_STATUS_OK, pelage_guide_cache_read(cache, quantized, &set, 0, decoded, heard));
    CHECK(progress_rose(&seen));
    const int calls = seen.calls;
    /* cancelled while unpacking: the frame keeps its guides */
    stop = progress_new(1), heard.progress_user_data = &stop;
    EXPECT(PELAGE_STATUS_CANCELLED, pelage_guide_cache_read(cache, quantized, &set, 0, decoded, heard));
    EXPECT(PELAGE_STATUS_OK, expand_(decoded, roots, bindings, grooms, n, &g_in.expand_params, g_in.points_out, 16,
                                     POINTS_CAPACITY, NULL, NULL));
    /* cancelled while posing: the frame has no guides until the next read */
    stop = progress_new(calls), heard.progress_user_data = &stop;
    EXPECT(PELAGE_STATUS_CANCELLED, pelage_guide_cache_read(cache, quantized, &set, 0, decoded, heard));
    EXPECT(PELAGE_STATUS_INVALID_ARGUMENT, expand_(decoded, roots, bindings, grooms, n, &g_in.expand_params,
                                                   g_in.points_out, 16, POINTS_CAPACITY, NULL, NULL));
    EXPECT(PELAGE_STATUS_OK, pelage_guide_cache_read(cache, quantized, &set, 0, decoded, threads_run(1)));
    free(again);
  }

  /* patch boxes hold every point of their strands */
  float *boxes = malloc(patch_count * 6 * sizeof *boxes);
  REQUIRE(boxes);
  EXPECT(PELAGE_STATUS_OK, pelage_patch_boxes(decoded, &strands, &g_in.expand_params, patches, patch_count, boxes));
  EXPECT(PELAGE_STATUS_OK, expand_(decoded, roots, bindings, grooms, n, &g_in.expand_params, g_in.points_out, 16,
                                   POINTS_CAPACITY, NULL, NULL));
  size_t outside = 0;
  for (size_t p = 0; p < patch_count; ++p) {
    const float *b = boxes + 6 * p;
    for (size_t k = patches[p].first * g_in.per; k < (size_t)(patches[p].first + patches[p].count) * g_in.per; ++k) {
      const float *q = (const float *)(g_in.points_out + 16 * k);
      for (int a = 0; a < 3; ++a) outside += q[a] - q[3] < b[a] || q[a] + q[3] > b[3 + a];
    }
  }
  CHECK(outside == 0);
  PelagePatch past = {(uint32_t)n, 1};
  EXPECT(PELAGE_STATUS_OUT_OF_RANGE, pelage_patch_boxes(decoded, &strands, &g_in.expand_params, &past, 1, boxes));
  pelage_frame_free(decoded);
  free(boxes), free(cache), free(file), free(guide_roots), free(guide_points), free(roots2), free(bindings2);
  free(grooms2), free(patches2), free(roots), free(bindings), free(grooms), free(order), free(patches);
}

static void interp_free(void) {
  pelage_frame_free(g_in.frame);
  free(g_in.guide_roots), free(g_in.strands), free(g_in.guide_points), free(g_in.bind_arena), free(g_in.bindings);
  free(g_in.grooms), free(g_in.points), free(g_in.bind_out), free(g_in.groom_out);
  free(g_in.points_out), free(g_in.counts_out), free(g_in.ids_out), free(g_in.index_out);
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
  g_worker_status = pelage_stamp_size(mesh, &p, &a, &b);
  snprintf(g_worker_after, sizeof g_worker_after, "%s", pelage_last_error());
  return NULL;
}

/* Strands of `grooms` with a control point after the root deeper than 0.98
 * inside the unit sphere (the mesh lies between radius ~0.99 and 1). */
static size_t strands_inside(const PelageStrandGroom *grooms) {
  const size_t n = g_in.strand_count, per = g_in.per;
  float *pts = malloc(n * per * 16);
  REQUIRE(pts);
  EXPECT(PELAGE_STATUS_OK, expand_(g_in.frame, g_in.strands, g_in.bindings, grooms, n, &g_in.expand_params, pts, 16,
                                   n * per, NULL, NULL));
  size_t inside = 0;
  for (size_t i = 0; i < n; ++i) {
    int in = 0;
    for (size_t j = 2; j < per; ++j) {
      const float *q = &pts[4 * (i * per + j)];
      in |= q[0] * q[0] + q[1] * q[1] + q[2] * q[2] < 0.98f * 0.98f;
    }
    inside += (size_t)in;
  }
  free(pts);
  return inside;
}

/* Trimming, strand edits, LOD counts and masks (paper 3.3 and 4): the
 * happy path's consistency, then every failure with its status and nothing
 * written. */
static void test_trim_and_edits(void) {
  const size_t n = g_in.strand_count, per = g_in.per, g = g_in.guide_count;
  const uint32_t points = g_in.expand_params.points_per_strand;
  PelageGroom groom = NULL;
  PelageStrands r = records(g_in.strands, g_in.bindings, g_in.grooms, n);
  EXPECT(PELAGE_STATUS_OK, pelage_groom_new(&r, &groom));
  REQUIRE(groom != NULL);
  /* the half-space z > 1.05 over the unit sphere: the guides (0.2 long)
   * near the pole enter it */
  PelagePlane above = {{0.0f, 0.0f, -1.0f}, -1.05f};
  PelageColliders col;
  memset(&col, 0, sizeof col);
  col.planes = &above, col.plane_count = 1;
  PelageTrimRecord *rec = malloc(g * sizeof *rec), *back = malloc(g * sizeof *back);
  uint16_t *lengths = malloc(n * sizeof *lengths), *lengths_back = malloc((n + 1) * sizeof *lengths);
  REQUIRE(rec && back && lengths && lengths_back);
  size_t count = 0;
  EXPECT(PELAGE_STATUS_OK, pelage_trim_find(g_in.frame, NULL, &col, threads_run(2), rec, g, &count));
  CHECK(count > 0 && count < g);
  int sane = 1;
  for (size_t i = 0; i < count; ++i)
    sane &= (i == 0 || rec[i].guide > rec[i - 1].guide) && rec[i].cv >= 1 && rec[i].cv < points && rec[i].length > 0.0f && rec[i].length < 1.0f;
  CHECK(sane);
  {
    size_t one = 0;
    PelageTrimRecord first[1];
    EXPECT(PELAGE_STATUS_OK, pelage_trim_find(g_in.frame, NULL, &col, threads_run(1), rec, g, &one));
    CHECK(one == count);
    FILL(first, sizeof first);
    EXPECT(PELAGE_STATUS_CAPACITY_EXCEEDED, pelage_trim_find(g_in.frame, NULL, &col, threads_run(1), first, 1, &one));
    CHECK(one == count && untouched(first, sizeof first)); /* the count needed, no record */
  }
  {
    /* trim_find hears its progress; cancelled, it writes nothing */
    Progress seen = progress_new(0), stop = progress_new(2);
    PelageRun heard = threads_run(2);
    heard.progress = on_progress, heard.progress_user_data = &seen;
    size_t again = 0;
    FILL(back, g * sizeof *back);
    EXPECT(PELAGE_STATUS_OK, pelage_trim_find(g_in.frame, NULL, &col, heard, back, g, &again));
    CHECK(again == count && memcmp(back, rec, count * sizeof *rec) == 0 && progress_rose(&seen));
    heard.progress_user_data = &stop;
    FILL(back, g * sizeof *back), FILL(&again, sizeof again);
    EXPECT(PELAGE_STATUS_CANCELLED, pelage_trim_find(g_in.frame, NULL, &col, heard, back, g, &again));
    CHECK(stop.calls == 2 && untouched(back, g * sizeof *back) && untouched(&again, sizeof again));
  }
  FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_trim_find(NULL, NULL, &col, threads_run(1), rec, g, &count));
  FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_trim_find(g_in.frame, NULL, &col, threads_run(1), rec, g, NULL));
  {
    PelageSphere bad = {{0.0f, 0.0f, 0.0f}, -1.0f};
    PelageColliders c = col;
    c.spheres = &bad, c.sphere_count = 1;
    FILL(back, g * sizeof *back);
    EXPECT(PELAGE_STATUS_INVALID_ARGUMENT, pelage_trim_find(g_in.frame, NULL, &c, threads_run(1), back, g, &count));
    CHECK(untouched(back, g * sizeof *back));
  }

  /* the records file: round trip, then damage */
  size_t size = 0, written = 0;
  EXPECT(PELAGE_STATUS_OK, pelage_trim_records_size(count, &size));
  unsigned char *file = malloc(size);
  REQUIRE(file);
  EXPECT(PELAGE_STATUS_OK, pelage_trim_records_write(rec, count, g, points, file, size, &written));
  CHECK(written == size);
  PelageTrimRecordsInfo info;
  EXPECT(PELAGE_STATUS_OK, pelage_trim_records_read(file, size, back, g, &info));
  CHECK(info.guide_count == g && info.points_per_guide == points && info.record_count == count);
  CHECK(memcmp(back, rec, count * sizeof *rec) == 0);
  FILL(back, g * sizeof *back);
  EXPECT(PELAGE_STATUS_CORRUPT_DATA, pelage_trim_records_read(file, size - 1, back, g, &info));
  EXPECT(PELAGE_STATUS_CAPACITY_EXCEEDED, pelage_trim_records_read(file, size, back, count - 1, &info));
  file[size - 1] ^= 1;
  EXPECT(PELAGE_STATUS_CORRUPT_DATA, pelage_trim_records_read(file, size, back, g, &info));
  file[size - 1] ^= 1, file[0] ^= 1;
  EXPECT(PELAGE_STATUS_VERSION_MISMATCH, pelage_trim_records_info(file, size, &info));
  CHECK(untouched(back, g * sizeof *back));
  EXPECT(PELAGE_STATUS_CAPACITY_EXCEEDED, pelage_trim_records_write(rec, count, g, points, file, size - 1, &written));
  {
    PelageTrimRecord bad = rec[0];
    bad.guide = (uint32_t)g;
    EXPECT(PELAGE_STATUS_OUT_OF_RANGE, pelage_trim_records_write(&bad, 1, g, points, file, size, &written));
  }

  /* the shot pass from the records, and from the hairs themselves */
  for (size_t i = 0; i < n; ++i) lengths[i] = PELAGE_TRIM_WHOLE;
  EXPECT(PELAGE_STATUS_OK, pelage_trim_shortest(groom, rec, count, g, points, lengths, n));
  size_t cut = 0;
  for (size_t i = 0; i < n; ++i) cut += lengths[i] < PELAGE_TRIM_WHOLE;
  CHECK(cut > 0 && cut < n);
  {
    PelageTrimRecord bad = rec[0];
    bad.cv = points;
    memcpy(lengths_back, lengths, n * sizeof *lengths);
    EXPECT(PELAGE_STATUS_OUT_OF_RANGE, pelage_trim_shortest(groom, &bad, 1, g, points, lengths, n));
    bad = rec[0], bad.length = NAN;
    EXPECT(PELAGE_STATUS_NON_FINITE, pelage_trim_shortest(groom, &bad, 1, g, points, lengths, n));
    EXPECT(PELAGE_STATUS_INVALID_ARGUMENT, pelage_trim_shortest(groom, rec, count, g, points, lengths, n - 1));
    EXPECT(PELAGE_STATUS_INVALID_ARGUMENT, pelage_trim_shortest(groom, rec, count, SIZE_MAX, points, lengths, n));
    EXPECT(PELAGE_STATUS_OUT_OF_RANGE, pelage_trim_shortest(groom, rec, count, 1, points, lengths, n));
    CHECK(memcmp(lengths_back, lengths, n * sizeof *lengths) == 0);
  }
  {
    uint16_t *own = malloc(n * sizeof *own);
    REQUIRE(own);
    for (size_t i = 0; i < n; ++i) own[i] = PELAGE_TRIM_WHOLE;
    EXPECT(PELAGE_STATUS_OK, pelage_trim_shortest_hairs(groom, g_in.frame, NULL, &col, &g_in.expand_params, own, n));
    size_t own_cut = 0;
    for (size_t i = 0; i < n; ++i) own_cut += own[i] < PELAGE_TRIM_WHOLE;
    CHECK(own_cut > 0 && own_cut < n);
    EXPECT(PELAGE_STATUS_NULL_PARAMETER,
           pelage_trim_shortest_hairs(NULL, g_in.frame, NULL, &col, &g_in.expand_params, own, n));
    EXPECT(PELAGE_STATUS_INVALID_ARGUMENT,
           pelage_trim_shortest_hairs(groom, g_in.frame, NULL, &col, &g_in.expand_params, own, n + 1));
    free(own);
  }

  /* the lengths file */
  EXPECT(PELAGE_STATUS_OK, pelage_trim_lengths_size(n, &size));
  CHECK(size == 40 + (n + 1) / 2 * 4);
  unsigned char *lfile = malloc(size);
  REQUIRE(lfile);
  EXPECT(PELAGE_STATUS_OK, pelage_trim_lengths_write(lengths, n, lfile, size, &written));
  size_t strands = 0;
  EXPECT(PELAGE_STATUS_OK, pelage_trim_lengths_read(lfile, size, lengths_back, n, &strands));
  CHECK(strands == n && memcmp(lengths_back, lengths, n * sizeof *lengths) == 0);
  FILL(lengths_back, n * sizeof *lengths);
  strands = 0;
  EXPECT(PELAGE_STATUS_CAPACITY_EXCEEDED, pelage_trim_lengths_read(lfile, size, lengths_back, n - 1, &strands));
  CHECK(strands == n && untouched(lengths_back, n * sizeof *lengths));
  EXPECT(PELAGE_STATUS_CORRUPT_DATA, pelage_trim_lengths_read(lfile, size - 4, lengths_back, n, &strands));
  EXPECT(PELAGE_STATUS_INVALID_ARGUMENT, pelage_trim_lengths_size(SIZE_MAX, &size));

  /* expansion with edits: none changes nothing; a cut; a push mask needs colliders */
  unsigned char *mask = malloc(n);
  REQUIRE(mask);
  memset(mask, 1, n);
  PelageStrandEdits edits;
  edits.lengths = NULL, edits.push_mask = NULL;
  PelageCurves c = curves_of(g_in.points_out, 16, n * per, NULL, NULL);
  FILL(g_in.points_out, points_out_bytes());
  EXPECT(PELAGE_STATUS_OK, pelage_groom_expand_edited(groom, g_in.frame, 0, n, &edits, &g_in.expand_params, &c));
  CHECK(memcmp(g_in.points_out, g_in.points, n * per * 16) == 0);
  edits.lengths = lengths;
  EXPECT(PELAGE_STATUS_OK, pelage_groom_expand_edited(groom, g_in.frame, 0, n, &edits, &g_in.expand_params, &c));
  CHECK(memcmp(g_in.points_out, g_in.points, n * per * 16) != 0);
  edits.lengths = (const uint16_t *)(const void *)((const unsigned char *)lengths_back + 1);
  FAILS(PELAGE_STATUS_MISALIGNED, pelage_groom_expand_edited(groom, g_in.frame, 0, n, &edits, &g_in.expand_params, &c));
  edits.lengths = NULL, edits.push_mask = mask;
  FAILS(PELAGE_STATUS_INVALID_ARGUMENT,
        pelage_groom_expand_edited(groom, g_in.frame, 0, n, &edits, &g_in.expand_params, &c));
  {
    PelageSphere bad = {{0.0f, 0.0f, NAN}, 1.0f};
    PelageColliders b = col;
    b.spheres = &bad, b.sphere_count = 1;
    EXPECT(PELAGE_STATUS_NON_FINITE, pelage_frame_set_colliders(g_in.frame, &b, threads_run(1)));
  }
  EXPECT(PELAGE_STATUS_OK, pelage_frame_set_colliders(g_in.frame, &col, threads_run(0)));
  EXPECT(PELAGE_STATUS_OK, pelage_groom_expand_edited(groom, g_in.frame, 0, n, &edits, &g_in.expand_params, &c));
  EXPECT(PELAGE_STATUS_OK, pelage_frame_set_colliders(g_in.frame, NULL, threads_run(1)));
  FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_frame_set_colliders(NULL, &col, threads_run(1)));
  {
    /* the body's build and the posing hear their progress and can be cancelled */
    PelageColliders with_body = col;
    with_body.body = 1;
    Progress seen = progress_new(0), stop = progress_new(2);
    PelageRun heard = threads_run(2);
    heard.progress = on_progress, heard.progress_user_data = &seen;
    EXPECT(PELAGE_STATUS_OK, pelage_frame_set_colliders(g_in.frame, &with_body, heard));
    CHECK(progress_rose(&seen) && seen.calls >= 5);
    heard.progress_user_data = &stop;
    EXPECT(PELAGE_STATUS_CANCELLED, pelage_frame_set_colliders(g_in.frame, &with_body, heard));
    CHECK(stop.calls == 2);
    EXPECT(PELAGE_STATUS_OK, pelage_frame_set_colliders(g_in.frame, NULL, threads_run(1)));
    seen = progress_new(0), heard.progress_user_data = &seen;
    EXPECT(PELAGE_STATUS_OK, pelage_frame_set_guides(g_in.frame, &g_in.guides, heard));
    CHECK(progress_rose(&seen));
    stop = progress_new(seen.calls), heard.progress_user_data = &stop;
    EXPECT(PELAGE_STATUS_CANCELLED, pelage_frame_set_guides(g_in.frame, &g_in.guides, heard));
    FAILS(PELAGE_STATUS_INVALID_ARGUMENT, pelage_groom_expand(groom, g_in.frame, 0, n, &g_in.expand_params, &c));
    EXPECT(PELAGE_STATUS_OK, pelage_frame_set_guides(g_in.frame, &g_in.guides, threads_run(1)));
    EXPECT(PELAGE_STATUS_OK, pelage_groom_expand(groom, g_in.frame, 0, n, &g_in.expand_params, &c));
  }
  {
    /* the inside rule for host points: the sphere's centre is inside, a
     * point beyond it and one a hair outside its skin are not; the same
     * answers with the frame's own body and with one built for the call */
    const float pts[4][3] = {{0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 2.0f}, {0.0f, 0.0f, 0.9f}, {0.0f, 0.0f, 1.05f}};
    uint8_t in[4], again[4];
    FILL(in, sizeof in);
    EXPECT(PELAGE_STATUS_OK, pelage_frame_inside(g_in.frame, pts, 12, 4, threads_run(2), in));
    CHECK(in[0] == 1 && in[1] == 0 && in[2] == 1 && in[3] == 0);
    PelageColliders with_body = col;
    with_body.body = 1;
    EXPECT(PELAGE_STATUS_OK, pelage_frame_set_colliders(g_in.frame, &with_body, threads_run(1)));
    EXPECT(PELAGE_STATUS_OK, pelage_frame_inside(g_in.frame, pts, 12, 4, threads_run(1), again));
    CHECK(memcmp(in, again, sizeof in) == 0);
    EXPECT(PELAGE_STATUS_OK, pelage_frame_set_colliders(g_in.frame, NULL, threads_run(1)));
    float bad[2][3] = {{0.0f, 0.0f, 0.0f}, {0.0f, NAN, 0.0f}};
    FILL(again, sizeof again);
    EXPECT(PELAGE_STATUS_NON_FINITE, pelage_frame_inside(g_in.frame, bad, 12, 2, threads_run(1), again));
    bad[1][1] = 2e9f;
    EXPECT(PELAGE_STATUS_INVALID_ARGUMENT, pelage_frame_inside(g_in.frame, bad, 12, 2, threads_run(1), again));
    CHECK(untouched(again, sizeof again));
    FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_frame_inside(NULL, pts, 12, 4, threads_run(1), in));
    FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_frame_inside(g_in.frame, NULL, 12, 4, threads_run(1), in));
    FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_frame_inside(g_in.frame, pts, 12, 4, threads_run(1), NULL));
    EXPECT(PELAGE_STATUS_OK, pelage_frame_inside(g_in.frame, NULL, 12, 0, threads_run(1), NULL));
    Progress stop = progress_new(1);
    PelageRun heard = threads_run(1);
    heard.progress = on_progress, heard.progress_user_data = &stop;
    EXPECT(PELAGE_STATUS_CANCELLED, pelage_frame_inside(g_in.frame, pts, 12, 4, heard, in));
    /* the signed distance: negative where inside, about the sphere's
     * radius at its centre, a hair's length off its skin */
    float d[4];
    FILL(d, sizeof d);
    EXPECT(PELAGE_STATUS_OK, pelage_frame_signed_distance(g_in.frame, pts, 12, 4, threads_run(2), d));
    for (int i = 0; i < 4; i++) CHECK((d[i] < 0.0f) == (in[i] == 1));
    CHECK(fabsf(d[0] + 1.0f) < 0.05f && fabsf(d[1] - 1.0f) < 0.05f);
    CHECK(fabsf(d[2] + 0.1f) < 0.05f && fabsf(d[3] - 0.05f) < 0.05f);
    float d_again[4];
    EXPECT(PELAGE_STATUS_OK, pelage_frame_signed_distance(g_in.frame, pts, 12, 4, threads_run(1), d_again));
    CHECK(memcmp(d, d_again, sizeof d) == 0);
    FILL(d_again, sizeof d_again);
    EXPECT(PELAGE_STATUS_INVALID_ARGUMENT, pelage_frame_signed_distance(g_in.frame, bad, 12, 2, threads_run(1), d_again));
    bad[1][1] = NAN;
    EXPECT(PELAGE_STATUS_NON_FINITE, pelage_frame_signed_distance(g_in.frame, bad, 12, 2, threads_run(1), d_again));
    CHECK(untouched(d_again, sizeof d_again));
    FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_frame_signed_distance(NULL, pts, 12, 4, threads_run(1), d));
    FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_frame_signed_distance(g_in.frame, pts, 12, 4, threads_run(1), NULL));
    EXPECT(PELAGE_STATUS_OK, pelage_frame_signed_distance(g_in.frame, NULL, 12, 0, threads_run(1), NULL));
    stop = progress_new(1);
    EXPECT(PELAGE_STATUS_CANCELLED, pelage_frame_signed_distance(g_in.frame, pts, 12, 4, heard, d));
  }
  {
    /* the frame's origin: zero when new, kept as given, refused when not
     * finite or beyond 1e15 (and then unchanged) */
    double at[3] = {1.0, 1.0, 1.0};
    EXPECT(PELAGE_STATUS_OK, pelage_frame_origin(g_in.frame, at));
    CHECK(at[0] == 0.0 && at[1] == 0.0 && at[2] == 0.0);
    const double far[3] = {1e4, -2.5e3, 123456.789};
    EXPECT(PELAGE_STATUS_OK, pelage_frame_set_origin(g_in.frame, far));
    EXPECT(PELAGE_STATUS_OK, pelage_frame_origin(g_in.frame, at));
    CHECK(memcmp(at, far, sizeof at) == 0);
    const double nan_at[3] = {0.0, NAN, 0.0}, huge[3] = {0.0, 0.0, 2e15};
    EXPECT(PELAGE_STATUS_NON_FINITE, pelage_frame_set_origin(g_in.frame, nan_at));
    EXPECT(PELAGE_STATUS_INVALID_ARGUMENT, pelage_frame_set_origin(g_in.frame, huge));
    EXPECT(PELAGE_STATUS_OK, pelage_frame_origin(g_in.frame, at));
    CHECK(memcmp(at, far, sizeof at) == 0);
    FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_frame_set_origin(NULL, far));
    FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_frame_set_origin(g_in.frame, NULL));
    FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_frame_origin(NULL, at));
    FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_frame_origin(g_in.frame, NULL));
    FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_sim_origin(NULL, at));
    const double zero[3] = {0.0, 0.0, 0.0};
    EXPECT(PELAGE_STATUS_OK, pelage_frame_set_origin(g_in.frame, zero));
  }

  /* LOD counts need patches sorted by rank; masks need a finite threshold */
  {
    PelagePatch one = {0, 1}, all = {0, (uint32_t)n};
    uint32_t kept = 7;
    EXPECT(PELAGE_STATUS_OK, pelage_groom_lod_counts(groom, &one, 1, UINT32_MAX, &kept));
    CHECK(kept == 1);
    EXPECT(PELAGE_STATUS_INVALID_ARGUMENT, pelage_groom_lod_counts(groom, &all, 1, (uint32_t)n / 2, &kept));
    PelagePatch past = {(uint32_t)n, 1};
    EXPECT(PELAGE_STATUS_OUT_OF_RANGE, pelage_groom_lod_counts(groom, &past, 1, 1, &kept));
    PelageMap m;
    memset(&m, 0, sizeof m);
    m.kind = PELAGE_MAP_KIND_CONSTANT, m.constant = 1.0f;
    memset(mask, 0, n);
    EXPECT(PELAGE_STATUS_OK, pelage_map_mask(&g_in.mesh, &m, g_in.strands, n, 0.5f, mask));
    size_t on = 0;
    for (size_t i = 0; i < n; ++i) on += mask[i] == 1;
    CHECK(on == n);
    EXPECT(PELAGE_STATUS_NON_FINITE, pelage_map_mask(&g_in.mesh, &m, g_in.strands, n, NAN, mask));
  }
  free(mask), free(lfile), free(file), free(rec), free(back), free(lengths), free(lengths_back);
  pelage_groom_free(groom);
}

static void test_settle(void) {
  const size_t n = g_in.strand_count, points = g_in.guide_count * GCVS;
  PelageExpandParams ep = g_in.expand_params;
  size_t bytes = 0;
  EXPECT(PELAGE_STATUS_NULL_PARAMETER, pelage_settle_size(&g_in.mesh, g_in.guide_count, &ep, NULL));
  EXPECT(PELAGE_STATUS_NULL_PARAMETER, pelage_settle_size(NULL, g_in.guide_count, &ep, &bytes));
  EXPECT(PELAGE_STATUS_NULL_PARAMETER, pelage_settle_size(&g_in.mesh, g_in.guide_count, NULL, &bytes));
  CHECK(bytes == 0);
  EXPECT(PELAGE_STATUS_OK, pelage_settle_size(&g_in.mesh, g_in.guide_count, &ep, &bytes));
  CHECK(bytes > 0);
  unsigned char *arena = malloc(bytes);
  PelageStrandGroom *work = malloc(n * sizeof *work), *tilted = malloc(n * sizeof *tilted),
                    *settled = malloc(n * sizeof *settled);
  REQUIRE(arena && work && tilted && settled);
  /* tip every strand 2 radians about its tangent: below its tangent plane */
  for (size_t i = 0; i < n; ++i) tilted[i] = g_in.grooms[i], tilted[i].lift[0] = 2.0f;
  const size_t before = strands_inside(tilted);
  CHECK(before > n / 2);
  PelageSettleInfo info, again, out_info;
  memcpy(settled, tilted, n * sizeof *work);
  EXPECT(PELAGE_STATUS_OK, pelage_settle(&(PelageRestPose){&g_in.mesh, &g_in.guides}, g_in.strands, g_in.bindings, settled, n, &ep, (PelageArena){arena, bytes}, &info));
  CHECK(info.lifted >= before && info.unresolved == 0);
  CHECK(strands_inside(settled) == 0);
  /* the same grooms on any thread count */
  for (uint32_t threads = 0; threads < 4; threads += 3) {
    ep.run.thread_count = threads;
    memcpy(work, tilted, n * sizeof *work);
    EXPECT(PELAGE_STATUS_OK, pelage_settle(&(PelageRestPose){&g_in.mesh, &g_in.guides}, g_in.strands, g_in.bindings, work, n, &ep, (PelageArena){arena, bytes}, &again));
    CHECK(memcmp(work, settled, n * sizeof *work) == 0 && memcmp(&info, &again, sizeof info) == 0);
  }
  ep = g_in.expand_params;
  /* settled grooms stay settled */
  memcpy(work, settled, n * sizeof *work);
  EXPECT(PELAGE_STATUS_OK, pelage_settle(&(PelageRestPose){&g_in.mesh, &g_in.guides}, g_in.strands, g_in.bindings, work, n, &ep, (PelageArena){arena, bytes}, NULL));
  CHECK(memcmp(work, settled, n * sizeof *work) == 0);

  /* failures leave the grooms and the info untouched */
#define SETTLE_FAILS(want, call)                                           \
  do {                                                                     \
    memcpy(work, tilted, n * sizeof *work);                                \
    FILL(&out_info, sizeof out_info);                                      \
    EXPECT(want, call);                                                    \
    CHECK(memcmp(work, tilted, n * sizeof *work) == 0);                    \
    CHECK(untouched(&out_info, sizeof out_info));                          \
  } while (0)
#define SETTLE(mesh, guides, bindings, params) \
  pelage_settle(&(PelageRestPose){mesh, guides}, g_in.strands, bindings, work, n, params, (PelageArena){arena, bytes}, &out_info)
  SETTLE_FAILS(PELAGE_STATUS_NULL_PARAMETER,
               pelage_settle(&(PelageRestPose){NULL, &g_in.guides}, g_in.strands, g_in.bindings, work, n, &ep, (PelageArena){arena, bytes}, &out_info));
  SETTLE_FAILS(PELAGE_STATUS_NULL_PARAMETER,
               pelage_settle(&(PelageRestPose){&g_in.mesh, NULL}, g_in.strands, g_in.bindings, work, n, &ep, (PelageArena){arena, bytes}, &out_info));
  SETTLE_FAILS(PELAGE_STATUS_NULL_PARAMETER,
               pelage_settle(&(PelageRestPose){&g_in.mesh, &g_in.guides}, NULL, g_in.bindings, work, n, &ep, (PelageArena){arena, bytes}, &out_info));
  SETTLE_FAILS(PELAGE_STATUS_NULL_PARAMETER,
               pelage_settle(&(PelageRestPose){&g_in.mesh, &g_in.guides}, g_in.strands, NULL, work, n, &ep, (PelageArena){arena, bytes}, &out_info));
  SETTLE_FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_settle(&(PelageRestPose){&g_in.mesh, &g_in.guides}, g_in.strands, g_in.bindings, NULL, n, &ep, (PelageArena){arena, bytes}, &out_info));
  SETTLE_FAILS(PELAGE_STATUS_NULL_PARAMETER, pelage_settle(&(PelageRestPose){&g_in.mesh, &g_in.guides}, g_in.strands, g_in.bindings, work, n, NULL, (PelageArena){arena, bytes}, &out_info));
  SETTLE_FAILS(PELAGE_STATUS_CAPACITY_EXCEEDED, pelage_settle(&(PelageRestPose){&g_in.mesh, &g_in.guides}, g_in.strands, g_in.bindings, work, n, &ep, (PelageArena){arena, bytes / 2}, &out_info));
  SETTLE_FAILS(PELAGE_STATUS_CAPACITY_EXCEEDED, pelage_settle(&(PelageRestPose){&g_in.mesh, &g_in.guides}, g_in.strands, g_in.bindings, work, n, &ep, (PelageArena){NULL, 0}, &out_info));
  tilted[5].lift[1] = NAN;
  SETTLE_FAILS(PELAGE_STATUS_NON_FINITE, SETTLE(&g_in.mesh, &g_in.guides, g_in.bindings, &ep));
  /* split over threads, the error still names the element in the whole array */
  ep.run.thread_count = 3;
  tilted[5].lift[1] = 0.0f, tilted[n - 2].kink_phase[0] = INFINITY;
  SETTLE_FAILS(PELAGE_STATUS_NON_FINITE, SETTLE(&g_in.mesh, &g_in.guides, g_in.bindings, &ep));
  char want[64];
  snprintf(want, sizeof want, "grooms at element %zu", n - 2);
  CHECK(strstr(pelage_last_error(), want) != NULL);
  tilted[n - 2] = g_in.grooms[n - 2], tilted[n - 2].lift[0] = 2.0f;
  ep.run.thread_count = 1;
  tilted[5].lift[1] = 3.0f; /* |lift| = sqrt(13) > pi */
  SETTLE_FAILS(PELAGE_STATUS_INVALID_ARGUMENT, SETTLE(&g_in.mesh, &g_in.guides, g_in.bindings, &ep));
  tilted[5].lift[1] = 0.0f;
  ep.end_points = 9;
  SETTLE_FAILS(PELAGE_STATUS_INVALID_ARGUMENT, SETTLE(&g_in.mesh, &g_in.guides, g_in.bindings, &ep));
  ep = g_in.expand_params;

  /* hostile inputs: binding weights outside 0..1 (or not finite), groom values beyond 1e6, mesh and
   * guide values beyond 1e9, orphan_length beyond 1e9: refused, the grooms untouched */
  {
    PelageStrandBinding *b = malloc(n * sizeof *b);
    float(*p)[3] = malloc(g_sphere.nv * sizeof *p), (*gp)[3] = malloc(points * sizeof *gp);
    REQUIRE(b && p && gp);
    const size_t bound = first_bound();
    const float weights[4] = {1e30f, -1.0f, NAN, INFINITY};
    const PelageStatus status[4] = {PELAGE_STATUS_INVALID_ARGUMENT, PELAGE_STATUS_INVALID_ARGUMENT,
                                    PELAGE_STATUS_NON_FINITE, PELAGE_STATUS_NON_FINITE};
    for (int i = 0; i < 4; ++i) {
      memcpy(b, g_in.bindings, n * sizeof *b);
      b[bound].weights[0] = weights[i];
      SETTLE_FAILS(status[i], SETTLE(&g_in.mesh, &g_in.guides, b, &ep));
      ep.run.thread_count = 3;
      SETTLE_FAILS(status[i], SETTLE(&g_in.mesh, &g_in.guides, b, &ep));
      ep.run.thread_count = 1;
    }
    free(b);
    tilted[n / 3].bend = 1e30f;
    SETTLE_FAILS(PELAGE_STATUS_INVALID_ARGUMENT, SETTLE(&g_in.mesh, &g_in.guides, g_in.bindings, &ep));
    tilted[n / 3].bend = g_in.grooms[n / 3].bend, tilted[n / 3].clump = -2e6f;
    SETTLE_FAILS(PELAGE_STATUS_INVALID_ARGUMENT, SETTLE(&g_in.mesh, &g_in.guides, g_in.bindings, &ep));
    tilted[n / 3].clump = g_in.grooms[n / 3].clump;
    const float huge[2] = {1e30f, 3e38f};
    for (int i = 0; i < 2; ++i) {
      PelageMeshDesc m = g_in.mesh;
      memcpy(p, g_sphere.p, g_sphere.nv * sizeof *p);
      p[g_sphere.nv / 2][0] = huge[i];
      m.positions = p;
      SETTLE_FAILS(PELAGE_STATUS_INVALID_ARGUMENT, SETTLE(&m, &g_in.guides, g_in.bindings, &ep));
      EXPECT(PELAGE_STATUS_INVALID_ARGUMENT, pelage_settle_size(&m, g_in.guide_count, &ep, &g_in.sizes_out[0]));
      PelageGuidesDesc g = g_in.guides;
      memcpy(gp, g_in.guide_points, points * sizeof *gp);
      gp[7 * GCVS + GCVS - 1][1] += huge[i];
      g.points = gp;
      SETTLE_FAILS(PELAGE_STATUS_INVALID_ARGUMENT, SETTLE(&g_in.mesh, &g, g_in.bindings, &ep));
    }
    ep.orphan_length = 1e30f;
    SETTLE_FAILS(PELAGE_STATUS_INVALID_ARGUMENT, SETTLE(&g_in.mesh, &g_in.guides, g_in.bindings, &ep));
    ep = g_in.expand_params;
    free(p), free(gp);
  }

  /* progress: a callback that goes on changes nothing (on any thread count) and rises to 1 on the
   * calling thread; one that stops cancels at once: no further call, info not written, and every
   * groom either untouched or settled (which ones is unspecified) */
  {
    for (uint32_t threads = 1; threads < 4; threads += 2) {
      Progress seen = progress_new(0);
      ep.run.thread_count = threads;
      ep.run.progress = on_progress, ep.run.progress_user_data = &seen;
      memcpy(work, tilted, n * sizeof *work);
      FILL(&again, sizeof again);
      EXPECT(PELAGE_STATUS_OK, SETTLE(&g_in.mesh, &g_in.guides, g_in.bindings, &ep));
      CHECK(memcmp(work, settled, n * sizeof *work) == 0 && memcmp(&out_info, &info, sizeof info) == 0);
      CHECK(progress_rose(&seen));
      if (threads == 1) {
        printf("settle progress: %d calls, first %.3f, last %.3f\n", seen.calls, seen.first, seen.last);
        const int stops[3] = {1, seen.calls / 2, seen.calls};
        for (int i = 0; i < 3; ++i) {
          Progress stop = progress_new(stops[i]);
          ep.run.progress_user_data = &stop;
          memcpy(work, tilted, n * sizeof *work);
          FILL(&out_info, sizeof out_info);
          EXPECT(PELAGE_STATUS_CANCELLED, SETTLE(&g_in.mesh, &g_in.guides, g_in.bindings, &ep));
          CHECK(stop.calls == stops[i]);
          CHECK(untouched(&out_info, sizeof out_info));
          CHECK(strstr(pelage_last_error(), "cancel") != NULL);
          size_t changed = 0, neither = 0;
          for (size_t k = 0; k < n; ++k) {
            const int same = memcmp(&work[k], &tilted[k], sizeof *work) == 0;
            changed += !same;
            neither += !same && memcmp(&work[k], &settled[k], sizeof *work) != 0;
          }
          printf("settle cancelled at call %d of %d: %zu of %zu grooms settled\n", stops[i], seen.calls, changed, n);
          CHECK(neither == 0);
        }
      }
    }
    ep = g_in.expand_params;
  }

  /* the legal extremes: a sphere of radius 5e8 and groom values of 1e6 settle to finite grooms
   * (or are refused) */
  {
    Scaled big = scaled_new(5e8f);
    size_t big_bytes = 0;
    EXPECT(PELAGE_STATUS_OK, pelage_settle_size(&big.mesh, g_in.guide_count, &ep, &big_bytes));
    unsigned char *big_arena = malloc(big_bytes);
    REQUIRE(big_arena);
    for (size_t i = 0; i < n; ++i) {
      work[i] = tilted[i];
      work[i].length = 1e6f, work[i].bend = 1e6f, work[i].kink_amplitude = -1e6f, work[i].kink_frequency = 1e6f;
      work[i].clump = 1e6f, work[i].root_radius = 1e6f;
    }
    ep.orphan_length = 1e9f;
    const PelageStatus st = pelage_settle(&(PelageRestPose){&big.mesh, &big.guides}, g_in.strands, g_in.bindings, work, n, &ep, (PelageArena){big_arena, big_bytes}, &out_info);
    size_t bad = 0;
    for (size_t i = 0; i < n; ++i) {
      bad += count_non_finite((const float *)(const void *)&work[i], sizeof *work / sizeof(float));
      bad += !(work[i].lift[0] * work[i].lift[0] + work[i].lift[1] * work[i].lift[1] <= 3.1416f * 3.1416f);
    }
    printf("settle: radius 5e8, groom values 1e6: %s, %zu bad values\n", status_name(st), bad);
    CHECK(st != PELAGE_STATUS_OK || bad == 0);
    ep = g_in.expand_params;
    free(big_arena);
    scaled_free(&big);
  }
#undef SETTLE
#undef SETTLE_FAILS
  printf("settle: %zu of %zu tilted strands inside; lifted %u (unclumped %u, turned %u, shortened %u)\n", before, n,
         info.lifted, info.unclumped, info.turned, info.shortened);
  free(arena), free(work), free(tilted), free(settled);
}

/* Progress on pelage_bind, pelage_expand and pelage_groom_expand: a callback that goes on changes no
 * bit (on any thread count) and hears a never-decreasing share ending at 1 on the calling thread; one
 * that returns false cancels at once (no further call). A cancelled bind writes nothing. */
static void test_interp_progress(void) {
  const size_t n = g_in.strand_count, per = g_in.per;
  const unsigned threads[2] = {1, 0};

  /* pelage_bind */
  int bind_calls = 0;
  for (int t = 0; t < 2; ++t) {
    PelageBindParams bp = g_in.bind_params;
    Progress seen = progress_new(0);
    bp.run.thread_count = threads[t], bp.run.progress = on_progress, bp.run.progress_user_data = &seen;
    fill_outputs();
    EXPECT(PELAGE_STATUS_OK, BIND(&g_in.mesh, &g_in.guides, g_in.strands, n, &bp, g_in.bind_arena,
                                  g_in.bind_arena_bytes, g_in.bind_out, n));
    CHECK(memcmp(g_in.bind_out, g_in.bindings, n * sizeof *g_in.bind_out) == 0);
    CHECK(memcmp(&g_in.info_out, &g_in.info, sizeof g_in.info) == 0);
    CHECK(progress_rose(&seen));
    bind_calls = seen.calls;
  }
  printf("bind progress: %d calls\n", bind_calls);
  {
    const int stops[3] = {1, bind_calls / 2, bind_calls};
    for (int i = 0; i < 3; ++i) {
      PelageBindParams bp = g_in.bind_params;
      Progress stop = progress_new(stops[i]);
      bp.run.progress = on_progress, bp.run.progress_user_data = &stop;
      FAILS(PELAGE_STATUS_CANCELLED, BIND(&g_in.mesh, &g_in.guides, g_in.strands, n, &bp, g_in.bind_arena,
                                          g_in.bind_arena_bytes, g_in.bind_out, n));
      CHECK(stop.calls == stops[i]);
      CHECK(strstr(pelage_last_error(), "cancel") != NULL);
    }
  }
  /* a callback is not called when the arguments are refused */
  {
    PelageBindParams bp = g_in.bind_params;
    Progress stop = progress_new(1);
    bp.run.progress = on_progress, bp.run.progress_user_data = &stop;
    FAILS(PELAGE_STATUS_CAPACITY_EXCEEDED, BIND(&g_in.mesh, &g_in.guides, g_in.strands, n, &bp, g_in.bind_arena,
                                                g_in.bind_arena_bytes, g_in.bind_out, n - 1));
    CHECK(stop.calls == 0);
  }

  /* pelage_expand and pelage_groom_expand */
  PelageGroom groom = NULL;
  {
    const PelageStrands r = records(g_in.strands, g_in.bindings, g_in.grooms, n);
    EXPECT(PELAGE_STATUS_OK, pelage_groom_new(&r, &groom));
    REQUIRE(groom != NULL);
  }
  for (int via_groom = 0; via_groom < 2; ++via_groom) {
    int calls = 0;
    for (int t = 0; t < 2; ++t) {
      PelageExpandParams ep = g_in.expand_params;
      Progress seen = progress_new(0);
      ep.run.thread_count = threads[t], ep.run.progress = on_progress, ep.run.progress_user_data = &seen;
      FILL(g_in.points_out, points_out_bytes()), FILL(g_in.counts_out, n * 4), FILL(g_in.ids_out, n * 4);
      EXPECT(PELAGE_STATUS_OK, via_groom ? GROOM_EXPAND(groom, g_in.frame, 0, n, &ep, g_in.points_out, n * per)
                                         : EXPAND(g_in.frame, g_in.strands, g_in.bindings, g_in.grooms, n, &ep,
                                                  g_in.points_out, 16, n * per));
      CHECK(memcmp(g_in.points_out, g_in.points, n * per * 16) == 0);
      CHECK(g_in.counts_out[n - 1] == per && g_in.ids_out[n - 1] == g_in.strands[n - 1].id);
      CHECK(progress_rose(&seen));
      calls = seen.calls;
    }
    printf("%s progress: %d calls\n", via_groom ? "groom_expand" : "expand", calls);
    const int stops[3] = {1, calls / 2, calls};
    for (int i = 0; i < 3; ++i) {
      PelageExpandParams ep = g_in.expand_params;
      Progress stop = progress_new(stops[i]);
      ep.run.progress = on_progress, ep.run.progress_user_data = &stop;
      /* the curves are unspecified after a cancel: only the status and the calls are checked */
      EXPECT(PELAGE_STATUS_CANCELLED, via_groom ? GROOM_EXPAND(groom, g_in.frame, 0, n, &ep, g_in.points_out, n * per)
                                                : EXPAND(g_in.frame, g_in.strands, g_in.bindings, g_in.grooms, n,
                                                         &ep, g_in.points_out, 16, n * per));
      CHECK(stop.calls == stops[i]);
      CHECK(strstr(pelage_last_error(), "cancel") != NULL);
    }
    /* refused arguments: no call */
    {
      PelageExpandParams ep = g_in.expand_params;
      Progress stop = progress_new(1);
      ep.run.progress = on_progress, ep.run.progress_user_data = &stop;
      FAILS(PELAGE_STATUS_CAPACITY_EXCEEDED,
            via_groom ? GROOM_EXPAND(groom, g_in.frame, 0, n, &ep, g_in.points_out, n * per - 1)
                      : EXPAND(g_in.frame, g_in.strands, g_in.bindings, g_in.grooms, n, &ep, g_in.points_out, 16,
                               n * per - 1));
      CHECK(stop.calls == 0);
    }
  }
  /* a patch of the groom: the callback hears that patch's share */
  {
    PelageExpandParams ep = g_in.expand_params;
    Progress seen = progress_new(0);
    ep.run.progress = on_progress, ep.run.progress_user_data = &seen;
    FILL(g_in.points_out, points_out_bytes());
    EXPECT(PELAGE_STATUS_OK, GROOM_EXPAND(groom, g_in.frame, n / 4, n / 2, &ep, g_in.points_out, (n / 2) * per));
    CHECK(memcmp(g_in.points_out, g_in.points + 4 * per * (n / 4), (n / 2) * per * 16) == 0);
    CHECK(progress_rose(&seen));
  }
  /* no strands: OK, and the share it hears still ends at 1 */
  {
    PelageExpandParams ep = g_in.expand_params;
    Progress seen = progress_new(0);
    ep.run.progress = on_progress, ep.run.progress_user_data = &seen;
    EXPECT(PELAGE_STATUS_OK, expand_(g_in.frame, NULL, NULL, NULL, 0, &ep, NULL, 16, 0, NULL, NULL));
    CHECK(!seen.decreased && !seen.outside && !seen.off_thread);
    CHECK(seen.calls >= 1 && seen.last == 1.0);
  }
  pelage_groom_free(groom);
}

static void test_threads(void) {
  const PelageMeshDesc mesh = sphere_desc(&g_sphere);
  size_t a, b;
  char mine[256];
  EXPECT(PELAGE_STATUS_NULL_PARAMETER, pelage_stamp_size(&mesh, NULL, &a, &b));
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

/* Progress rises to 1 without changing the roots; a false return at any call
 * cancels with nothing written. */
static void test_progress(void) {
  const PelageMeshDesc mesh = sphere_desc(&g_sphere);
  PelageStampParams p = g_params;
  Progress seen = progress_new(0);
  p.run.progress = on_progress;
  p.run.progress_user_data = &seen;
  PelageRoot *roots = malloc(g_capacity * sizeof *roots);
  REQUIRE(roots);
  size_t count = 0;
  EXPECT(PELAGE_STATUS_OK, pelage_stamp(&mesh, &p, (PelageArena){g_arena, g_arena_bytes}, roots, g_capacity, &count, NULL));
  CHECK(count == g_count && memcmp(roots, g_roots, g_count * sizeof *roots) == 0);
  CHECK(seen.calls >= 3 && progress_rose(&seen));
  /* the first call, one in the middle, and the last (1.0, before any root is written) */
  const int stops[3] = {1, seen.calls / 2, seen.calls};
  for (int i = 0; i < 3; i++) {
    const int at = stops[i];
    Progress stop = progress_new(at);
    p.run.progress_user_data = &stop;
    PelageStampInfo info;
    FILL(roots, g_capacity * sizeof *roots), FILL(&count, sizeof count), FILL(&info, sizeof info);
    EXPECT(PELAGE_STATUS_CANCELLED, pelage_stamp(&mesh, &p, (PelageArena){g_arena, g_arena_bytes}, roots, g_capacity, &count, &info));
    CHECK(stop.calls == at);
    CHECK(untouched(roots, g_capacity * sizeof *roots) && untouched(&count, sizeof count) &&
          untouched(&info, sizeof info));
    CHECK(strstr(pelage_last_error(), "cancel") != NULL);
  }
  free(roots);
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
  test_progress();
  test_evaluate();
  test_interp_defaults();
  test_interp_success();
  test_frame();
  test_interp_null_pointers();
  test_interp_capacity();
  test_interp_bad_input();
  test_hostile();
  test_groom_handle();
  test_trim_and_edits();
  test_settle();
  test_interp_progress();
  test_files();
  interp_free();
  test_threads();
  free(g_arena), free(g_roots);
  sphere_free(&g_sphere);
  printf("c_contract: %d checks, %d failed\n", g_checks, g_failures);
  return g_failures == 0 ? 0 : 1;
}

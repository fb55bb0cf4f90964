/* minimal.c: the smallest complete use of pelage's C API.
 *
 * Builds a 1 x 1 grid of triangles in code, asks pelage how much memory
 * stamping needs, stamps about 2,000 Poisson-spaced hair roots on it,
 * evaluates their positions and normals, and prints a few of them.
 *
 * Every pelage call returns a PelageStatus; pelage never allocates the
 * caller's outputs, and a failed call leaves them untouched. */
#include <pelage.h>

#include <stdio.h>
#include <stdlib.h>

#define N 16 /* grid cells per side */

/* Prints the status and pelage's detailed message, then exits on failure. */
static void check(PelageStatus status, const char *what) {
  if (status != PELAGE_STATUS_OK) {
    fprintf(stderr, "%s failed: %s (%s)\n", what, pelage_status_message(status), pelage_last_error());
    exit(EXIT_FAILURE);
  }
}

int main(void) {
  /* 1. A mesh: (N+1)^2 vertices on the z = 0 plane, two triangles per cell. */
  static float positions[(N + 1) * (N + 1)][3];
  static uint32_t triangles[2 * N * N][3];
  for (int y = 0; y <= N; ++y) {
    for (int x = 0; x <= N; ++x) {
      float *p = positions[y * (N + 1) + x];
      p[0] = (float)x / N;
      p[1] = (float)y / N;
      p[2] = 0.0f;
    }
  }
  for (int y = 0, t = 0; y < N; ++y) {
    for (int x = 0; x < N; ++x, t += 2) {
      uint32_t a = (uint32_t)(y * (N + 1) + x), b = a + 1, c = a + N + 2, d = a + N + 1;
      triangles[t][0] = a, triangles[t][1] = b, triangles[t][2] = c;
      triangles[t + 1][0] = a, triangles[t + 1][1] = c, triangles[t + 1][2] = d;
    }
  }
  PelageMeshDesc mesh = {0}; /* uvs and normals stay NULL: optional */
  mesh.positions = positions;
  mesh.position_stride = sizeof positions[0];
  mesh.vertex_count = (N + 1) * (N + 1);
  mesh.indices = triangles;
  mesh.index_stride = sizeof triangles[0];
  mesh.triangle_count = 2 * N * N;

  /* 2. Parameters: start from the defaults, then ask for ~2,000 roots. */
  PelageStampParams params = pelage_stamp_params_defaults();
  params.target_count = 2000;
  params.seed = 7;

  /* 3. Size the call: arena bytes and an upper bound on the root count. */
  size_t arena_bytes = 0, max_roots = 0;
  check(pelage_stamp_size(&mesh, &params, &arena_bytes, &max_roots), "pelage_stamp_size");
  void *arena = malloc(arena_bytes);
  PelageRoot *roots = malloc(max_roots * sizeof *roots);
  if (!arena || !roots) return EXIT_FAILURE;

  /* 4. Stamp. */
  size_t count = 0;
  PelageStampInfo info;
  check(pelage_stamp(&mesh, &params, (PelageArena){arena, arena_bytes}, roots, max_roots, &count, &info), "pelage_stamp");
  free(arena); /* scratch only: the roots do not point into it */

  /* 5. Evaluate root positions and normals (float3, packed). */
  float(*root_pos)[3] = malloc(count * sizeof *root_pos);
  float(*root_nrm)[3] = malloc(count * sizeof *root_nrm);
  if (!root_pos || !root_nrm) return EXIT_FAILURE;
  check(pelage_roots_evaluate(&mesh, roots, count, root_pos, sizeof *root_pos, root_nrm, sizeof *root_nrm),
        "pelage_roots_evaluate");

  printf("pelage %u.%u.%u: %zu roots (target %u), disk radius %.5f, %u passes, %u pruned\n",
         PELAGE_VERSION_MAJOR, PELAGE_VERSION_MINOR, PELAGE_VERSION_PATCH, count, params.target_count,
         info.radius, info.passes, info.pruned);
  for (size_t i = 0; i < count && i < 5; ++i) {
    printf("  root %u (rank %4u): face %3u  u %.3f v %.3f  at (%.4f, %.4f, %.4f)  normal (%g, %g, %g)\n",
           roots[i].id, roots[i].rank, roots[i].face, roots[i].u, roots[i].v, root_pos[i][0], root_pos[i][1],
           root_pos[i][2], root_nrm[i][0], root_nrm[i][1], root_nrm[i][2]);
  }
  free(root_pos);
  free(root_nrm);
  free(roots);
  return EXIT_SUCCESS;
}

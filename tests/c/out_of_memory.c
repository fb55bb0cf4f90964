/* Memory the system refuses is a status, not an abort of the host.
 *
 * Under an address-space limit (RLIMIT_AS) far below what a frame for
 * 2^26 guides of 64 points needs (103 GB), pelage_frame_new returns
 * PELAGE_STATUS_OUT_OF_MEMORY with a message and leaves its output alone;
 * the process lives on, and a frame that fits is then made as usual.
 * A test of its own: it changes a process-wide limit, which the sanitizer
 * and Valgrind runs of the contract test could not live under. Linux only
 * (elsewhere the limit may not bind, and the test exits 77: skipped). */
#include <pelage.h>

#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <sys/resource.h>

static int failures = 0;
#define CHECK(cond)                                                \
  do {                                                             \
    if (!(cond)) {                                                 \
      fprintf(stderr, "%s:%d: CHECK(%s) failed\n", __FILE__, __LINE__, #cond); \
      ++failures;                                                  \
    }                                                              \
  } while (0)

int main(void) {
#ifndef __linux__
  printf("out_of_memory: RLIMIT_AS is enforced only on Linux; skipped\n");
  return 77;
#else
  const float positions[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  const uint32_t indices[2][3] = {{0, 1, 2}, {1, 3, 2}};
  PelageMeshDesc mesh;
  memset(&mesh, 0, sizeof mesh);
  mesh.positions = positions;
  mesh.position_stride = sizeof positions[0];
  mesh.vertex_count = 4;
  mesh.indices = indices;
  mesh.index_stride = sizeof indices[0];
  mesh.triangle_count = 2;

  struct rlimit old, low;
  if (getrlimit(RLIMIT_AS, &old) != 0) {
    perror("getrlimit");
    return 1;
  }
  low = old;
  low.rlim_cur = (rlim_t)8 << 30; /* 8 GB: far above this test's own use */
  if (old.rlim_cur != RLIM_INFINITY && old.rlim_cur < low.rlim_cur) low.rlim_cur = old.rlim_cur;
  if (setrlimit(RLIMIT_AS, &low) != 0) {
    perror("setrlimit");
    return 1;
  }

  PelageFrame frame = (PelageFrame)(uintptr_t)0x1;
  PelageStatus s = pelage_frame_new(&mesh, (size_t)1 << 26, 64, &frame);
  CHECK(s == PELAGE_STATUS_OUT_OF_MEMORY);
  CHECK(frame == (PelageFrame)(uintptr_t)0x1); /* untouched */
  CHECK(strstr(pelage_last_error(), "cannot allocate") != NULL);
  CHECK(strcmp(pelage_status_message(s), "out of memory") == 0);
  printf("refused: %s (%s)\n", pelage_status_message(s), pelage_last_error());

  frame = NULL;
  s = pelage_frame_new(&mesh, 1000, 16, &frame);
  CHECK(s == PELAGE_STATUS_OK && frame != NULL);
  pelage_frame_free(frame);

  setrlimit(RLIMIT_AS, &old);
  if (failures) {
    fprintf(stderr, "%d check(s) failed\n", failures);
    return 1;
  }
  printf("out_of_memory: ok\n");
  return 0;
#endif
}

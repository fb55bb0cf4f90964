// A host linking the installed pelage: stamps a few roots on one triangle.
#include <pelage.h>

#include <cstdio>
#include <vector>

int main() {
  const float positions[3][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const uint32_t triangle[3] = {0, 1, 2};
  PelageMeshDesc mesh{};
  mesh.positions = positions, mesh.position_stride = sizeof positions[0], mesh.vertex_count = 3;
  mesh.indices = triangle, mesh.index_stride = sizeof triangle, mesh.triangle_count = 1;
  PelageStampParams params = pelage_stamp_params_defaults();
  params.target_count = 100;
  size_t arena_bytes = 0, max_roots = 0, count = 0;
  if (pelage_stamp_size(&mesh, &params, &arena_bytes, &max_roots) != PELAGE_STATUS_OK) return 1;
  std::vector<unsigned char> arena(arena_bytes);
  std::vector<PelageRoot> roots(max_roots);
  const PelageStatus s = pelage_stamp(&mesh, &params, PelageArena{arena.data(), arena.size()}, roots.data(), roots.size(), &count, nullptr);
  std::printf("consumer: pelage %u, %s, %zu roots\n", pelage_version(), pelage_status_message(s), count);
  return s == PELAGE_STATUS_OK && count > 90 && count < 110 ? 0 : 1;
}

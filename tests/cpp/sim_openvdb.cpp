// The guide simulation's host signed-distance collider on a real level set:
// OpenVDB (Debian's libopenvdb-dev) builds narrow-band level sets of two
// props (a ball and a box) that sit in the creature's fur, just clear of its
// skin; pelage_sim_step samples them through the distance callback, from
// its worker threads. After each step no guide point may have a negative
// distance (the same sampler decides), the guides that crossed the props
// must have been pushed out, and the bits must not depend on the thread
// count.
//
//   sim_openvdb <creature.obj>

#include <openvdb/openvdb.h>
#include <openvdb/tools/Composite.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/LevelSetSphere.h>
#include <openvdb/tools/MeshToVolume.h>

#include <cstdio>
#include <cstring>
#include <vector>

#include "creature_io.h"
#include "pelage.h"

namespace {

constexpr uint32_t kJoints = 12;
constexpr float kVoxel = 0.004f;

int g_failures = 0;

void expect(bool ok, const char* what) {
  if (!ok) {
    std::printf("FAILED: %s\n", what);
    ++g_failures;
  }
}

using Sampler = openvdb::tools::GridSampler<openvdb::FloatTree, openvdb::tools::BoxSampler>;

// pelage's distance callback: trilinear samples of the level set, in world
// space; a sampler per call (the tree is read-only, so threads share it).
void distances(void* user, const float* points, size_t count, float* out) {
  const auto& grid = *static_cast<const openvdb::FloatGrid*>(user);
  Sampler sampler(grid.tree(), grid.transform());
  for (size_t i = 0; i < count; ++i) {
    out[i] = sampler.wsSample(openvdb::Vec3R(points[3 * i], points[3 * i + 1], points[3 * i + 2]));
  }
}

// A box level set with corners lo, hi, as a union into `grid`.
void add_box(openvdb::FloatGrid& grid, creature::V3 lo, creature::V3 hi) {
  std::vector<openvdb::Vec3s> corners;
  for (int i = 0; i < 8; ++i) {
    corners.emplace_back(i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z);
  }
  const std::vector<openvdb::Vec4I> quads = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                            {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  const std::vector<openvdb::Vec3I> no_triangles;
  auto box = openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(grid.transform(), corners, no_triangles, quads, 3.0f);
  openvdb::tools::csgUnion(grid, *box);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: sim_openvdb <creature.obj>\n");
    return 2;
  }
  try {
    openvdb::initialize();
    const creature::Mesh mesh = creature::load_obj(argv[1]);
    PelageStampParams sp = pelage_stamp_params_defaults();
    sp.target_count = 3000;
    sp.seed = 1;
    const std::vector<PelageRoot> roots = creature::stamp(mesh, sp);
    const std::vector<float> points = creature::combed_guides(mesh, roots, kJoints, 0.08f);
    const PelageGuidesDesc guides = creature::guides_desc(roots, points, kJoints);
    std::vector<float> root_pos, root_nrm;
    creature::evaluate(mesh, roots, root_pos, root_nrm);

    // the props: a ball and a box, 0.015 off the skin above a root,
    // each wide enough to stand over several roots (3000 roots are about
    // 0.06 apart)
    auto grid = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(
        0.05f, openvdb::Vec3f(0, 0, 0), kVoxel, 3.0f);
    {
      const creature::V3 p = creature::at3(root_pos, 100), n = creature::at3(root_nrm, 100);
      const creature::V3 c = p + 0.095f * n;
      grid = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(0.08f, openvdb::Vec3f(c.x, c.y, c.z), kVoxel,
                                                                       3.0f);
      const creature::V3 q = creature::at3(root_pos, 2000), m = creature::at3(root_nrm, 2000);
      const creature::V3 b = q + 0.075f * m;
      add_box(*grid, b - creature::V3{0.06f, 0.06f, 0.06f}, b + creature::V3{0.06f, 0.06f, 0.06f});
    }
    // no root inside a prop: it would have no way out
    std::vector<float> d(roots.size());
    distances(grid.get(), root_pos.data(), roots.size(), d.data());
    size_t roots_inside = 0;
    for (float x : d) roots_inside += x < 0.0f;
    expect(roots_inside == 0, "the props are clear of every root");

    auto crossing = [&](const std::vector<float>& posed) {
      size_t guides_in = 0;
      std::vector<float> dist(kJoints);
      for (size_t g = 0; g < roots.size(); ++g) {
        distances(grid.get(), &posed[3 * g * kJoints], kJoints, dist.data());
        bool in = false;
        for (uint32_t k = 1; k < kJoints; ++k) in |= !(dist[k] >= 0.0f);
        guides_in += in;
      }
      return guides_in;
    };
    const size_t before = crossing(points);
    std::printf("guides crossing the props at rest: %zu of %zu\n", before, roots.size());
    expect(before >= 5, "the props are in the fur's way");

    const PelageMeshDesc desc = mesh.desc();
    PelageSimParams params = pelage_sim_params_defaults();
    params.joints = params.points_per_guide = kJoints;
    size_t bytes = 0;
    creature::check(pelage_sim_size(&desc, roots.size(), &params, &bytes), "pelage_sim_size");
    PelageFrame frame = nullptr;
    creature::check(pelage_frame_new(&desc, roots.size(), kJoints, &frame), "pelage_frame_new");
    creature::check(pelage_frame_set_guides(frame, &guides, PelageRun{0, nullptr, nullptr}), "pelage_frame_set_guides");
    PelageColliders colliders{};
    colliders.distance = distances;
    colliders.distance_user_data = grid.get();

    std::vector<std::vector<float>> runs;
    for (uint32_t threads : {1u, 2u}) {
      std::vector<unsigned char> memory(bytes);
      PelageSim sim = nullptr;
      const PelageRestPose rest_pose{&desc, &guides};
      creature::check(pelage_sim_new(&rest_pose, &params, PelageArena{memory.data(), bytes}, &sim), "pelage_sim_new");
      std::vector<float> posed(points.size());
      for (int step = 0; step < 3; ++step) {
        PelageStepParams step_params = pelage_step_params_defaults();
        step_params.colliders = &colliders;
        step_params.run.thread_count = threads;
        creature::check(pelage_sim_step(sim, frame, &step_params, nullptr), "pelage_sim_step");
        creature::check(pelage_sim_read(sim, posed.data(), 12, posed.size() / 3), "pelage_sim_read");
        const size_t left = crossing(posed);
        std::printf("%u thread(s), step %d: %zu guides with a point inside the props\n", threads, step, left);
        expect(left == 0, "no guide point inside a level-set prop after a step");
      }
      runs.push_back(posed);
      pelage_sim_free(sim);
    }
    expect(std::memcmp(runs[0].data(), runs[1].data(), runs[0].size() * sizeof(float)) == 0,
           "the same bits on 1 and 2 threads");
    pelage_frame_free(frame);
  } catch (const std::exception& e) {
    std::printf("FAILED: %s\n", e.what());
    return 1;
  }
  std::printf(g_failures ? "sim_openvdb: %d failures\n" : "sim_openvdb: ok\n", g_failures);
  return g_failures ? 1 : 0;
}

// A plugin-style simulation loop: what a DCC plugin does every frame with
// pelage's guide dynamics. The creature walks and sways; each frame the host
// makes the frame (deformed mesh and neutral guides), steps the simulation
// (tip springs, links, CCD IK, the body and a capsule as colliders), poses
// the frame's guides from the simulation, and expands the fur from them.
// Prints the time of each stage per frame.
//
//   sim_loop <creature.obj> [frames]

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "creature_io.h"

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: sim_loop <creature.obj> [frames]\n");
    return 2;
  }
  const int frames = argc > 2 ? std::atoi(argv[2]) : 24;
  using creature::check;
  try {
    const creature::Mesh rest = creature::load_obj(argv[1]);
    const PelageMeshDesc rest_desc = rest.desc();

    // Once per asset: guides, the render hairs bound to them, a groom.
    PelageStampParams sp = pelage_stamp_params_defaults();
    sp.target_count = 13030;
    sp.seed = 1;
    const std::vector<PelageRoot> guide_roots = creature::stamp(rest, sp);
    const uint32_t joints = 16;
    const std::vector<float> guide_points = creature::combed_guides(rest, guide_roots, joints, 0.06f);
    const PelageGuidesDesc guides = creature::guides_desc(guide_roots, guide_points, joints);
    sp.target_count = 200000;
    sp.seed = 2;
    const std::vector<PelageRoot> hairs = creature::stamp(rest, sp);
    PelageBindParams bp = pelage_bind_params_defaults();
    bp.run.thread_count = 0;
    const std::vector<PelageStrandBinding> bindings = creature::bind(rest, guides, hairs.data(), hairs.size(), bp);
    const std::vector<PelageStrandGroom> grooms =
        creature::groom(rest, pelage_groom_maps_defaults(), hairs.data(), hairs.size());
    const creature::Groom fur(hairs.data(), bindings.data(), grooms.data(), hairs.size());

    // Once per shot: the simulation, in the plugin's memory.
    PelageSimParams params = pelage_sim_params_defaults();
    params.link_radius = 0.05f;
    size_t bytes = 0;
    check(pelage_sim_size(&rest_desc, guide_roots.size(), &params, &bytes), "pelage_sim_size");
    std::vector<unsigned char> memory(bytes);
    PelageSim sim = nullptr;
    const PelageRestPose rest_pose{&rest_desc, &guides};
    check(pelage_sim_new(&rest_pose, &params, PelageArena{memory.data(), bytes}, &sim), "pelage_sim_new");

    PelageExpandParams ep = pelage_expand_params_defaults();
    ep.run.thread_count = 0;
    creature::Expander expander(ep);
    std::vector<float> curves(4 * expander.points_per_curve() * hairs.size());
    creature::Mesh posed = rest;
    std::printf("%5s | %9s %9s %9s %9s\n", "frame", "frame ms", "step ms", "expand ms", "total ms");
    for (int f = 0; f < frames; ++f) {
      const auto t0 = std::chrono::steady_clock::now();
      // the host's deformation: a walk along x and a sway of the upper body
      const float t = float(f) / 24.0f, sway = 0.08f * std::sin(6.2831853f * 1.5f * t);
      for (size_t v = 0; v < rest.vertex_count(); ++v) {
        const float up = std::fmax(rest.positions[3 * v + 1], 0.0f);
        posed.positions[3 * v] = rest.positions[3 * v] + sway * up * up + 1.2f * t;
      }
      PelageColliders colliders{};
      colliders.body = 1;
      const PelageCapsule stick = {{1.2f * t - 0.8f, 0.1f, 0.6f}, {1.2f * t + 0.8f, 0.1f, 0.6f}, 0.05f};
      colliders.capsules = &stick;
      colliders.capsule_count = 1;
      const creature::Frame frame(posed, guides, ep);
      const auto t1 = std::chrono::steady_clock::now();
      PelageStepParams step = pelage_step_params_defaults();
      step.colliders = &colliders;
      check(pelage_sim_step(sim, frame.get(), &step, nullptr), "pelage_sim_step");
      check(pelage_frame_set_sim_guides(frame.get(), sim, PelageRun{0, nullptr, nullptr}), "pelage_frame_set_sim_guides");
      const auto t2 = std::chrono::steady_clock::now();
      expander.expand(frame, fur, 0, hairs.size(), curves.data(), curves.size() / 4);
      const auto t3 = std::chrono::steady_clock::now();
      const auto ms = [](auto a, auto b) { return std::chrono::duration<double, std::milli>(b - a).count(); };
      std::printf("%5d | %9.1f %9.1f %9.1f %9.1f\n", f, ms(t0, t1), ms(t1, t2), ms(t2, t3), ms(t0, t3));
    }
    if (const size_t bad = creature::count_bad_points(curves.data(), curves.size() / 4)) {
      std::printf("FAILED: %zu control points are non-finite or have a negative radius\n", bad);
      return 1;
    }
    pelage_sim_free(sim);
  } catch (const std::exception& e) {
    std::printf("FAILED: %s\n", e.what());
    return 1;
  }
  return 0;
}

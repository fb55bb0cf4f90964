// demo.cpp: pelage's creature demo, the whole groom-to-render pipeline.
//
// Loads the creature mesh and its density map, stamps ~13,000 guide roots and
// ~1,000,000 render roots (Poisson, density-mapped), combs 16-point guides,
// binds the render hairs to the guides, samples the groom (kink, clump, bend,
// widths), settles the hairs out of the body, and expands every hair with pelage_expand straight into the float4
// vertex buffer Embree shares (round Catmull-Rom curves, pinned ends). Shadow
// rays see only the hairs with LOD rank < N/2 (half the hairs, as the paper's
// shadow pass), twice as wide so that their shadows are as dense as every
// hair's (PelageExpandParams.width_scale explains the factor): a second curve
// geometry over a copy of just those hairs. Renders fur.png.
//
// Then the guides are simulated (tip springs, links, the body as collider)
// while the creature shakes its upper body, the fur is expanded from the
// simulated guides each frame, and a strip of frames is written beside
// fur.png (fur_strip.png) with per-frame timings.
//
//   demo [creature.obj] [creature_density.png] [fur.png] [--roots N] [--guides N]
//        [--size PIXELS] [--spp SAMPLES] [--frames N] [--strip FRAMES]
#include "creature_io.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#ifndef PELAGE_ASSETS_DIR
#define PELAGE_ASSETS_DIR "assets"
#endif

namespace {

using creature::V3;

V3 lerp(V3 a, V3 b, float t) { return (1.0f - t) * a + t * b; }

struct Options {
  std::string obj = PELAGE_ASSETS_DIR "/creature.obj";
  std::string density = PELAGE_ASSETS_DIR "/creature_density.png";
  std::string out = "fur.png";
  uint32_t roots = 1000000;
  uint32_t guides = 13030;  // the paper's gorilla
  int size = 1024;
  int spp = 4;     // samples per pixel, a square number
  int frames = 3;  // expansions timed (the median is reported)
  int strip = 4;   // tiles in the simulated strip (3 steps each; 0: none)
};

Options parse(int argc, char** argv) {
  Options o;
  int positional = 0;
  for (int i = 1; i < argc; ++i) {
    const bool has_value = i + 1 < argc;
    if (!std::strcmp(argv[i], "--roots") && has_value) {
      o.roots = uint32_t(std::strtoul(argv[++i], nullptr, 10));
    } else if (!std::strcmp(argv[i], "--guides") && has_value) {
      o.guides = uint32_t(std::strtoul(argv[++i], nullptr, 10));
    } else if (!std::strcmp(argv[i], "--size") && has_value) {
      o.size = std::atoi(argv[++i]);
    } else if (!std::strcmp(argv[i], "--spp") && has_value) {
      o.spp = std::atoi(argv[++i]);
    } else if (!std::strcmp(argv[i], "--strip") && has_value) {
      o.strip = std::max(0, std::atoi(argv[++i]));
    } else if (!std::strcmp(argv[i], "--frames") && has_value) {
      o.frames = std::max(1, std::atoi(argv[++i]));
    } else if (argv[i][0] != '-' && positional < 3) {
      std::string* slots[3] = {&o.obj, &o.density, &o.out};
      *slots[positional++] = argv[i];
    } else {
      throw std::runtime_error(std::string("unknown argument ") + argv[i] +
                               "\nusage: demo [obj] [density.png] [out.png] [--roots N] [--guides N] [--size PIXELS] "
                               "[--spp N] [--frames N] [--strip N]");
    }
  }
  return o;
}

// A small counter-based hash for pixel jitter (same image at any thread count).
float hash01(uint32_t a, uint32_t b) {
  uint32_t h = a * 0x9E3779B1u ^ (b + 0x7F4A7C15u) * 0x85EBCA77u;
  h ^= h >> 15, h *= 0x2C1B3C6Du, h ^= h >> 12, h *= 0x297A2D39u, h ^= h >> 15;
  return float(h >> 8) * (1.0f / 16777216.0f);
}

struct Renderer {
  RTCScene scene;   // skin + every hair: camera rays
  RTCScene shadow;  // skin + the hairs with rank < N/2: shadow rays
  const creature::Mesh& mesh;
  const creature::GrayImage& density;
  unsigned mesh_id;
  RTCGeometry curves;
  unsigned segments_per_curve;
  V3 eye, forward, right, up;
  float tan_half_fov;
  V3 key = normalize(V3{-0.55f, 0.75f, 0.65f});  // key light direction (shadowed)

  bool occluded(V3 p, V3 dir) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRay ray{};
    ray.org_x = p.x, ray.org_y = p.y, ray.org_z = p.z;
    ray.dir_x = dir.x, ray.dir_y = dir.y, ray.dir_z = dir.z;
    ray.tnear = 2e-4f, ray.tfar = 1e30f, ray.mask = ~0u;
    rtcOccluded1(shadow, &ctx, &ray);
    return ray.tfar < 0.0f;
  }

  V3 shade(float px, float py, int size) const {
    const float sx = (2.0f * px / float(size) - 1.0f) * tan_half_fov;
    const float sy = (1.0f - 2.0f * py / float(size)) * tan_half_fov;
    const V3 dir = normalize(forward + sx * right + sy * up);
    const RTCRayHit rh = creature::trace(scene, eye, dir);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
      return lerp(V3{0.20f, 0.22f, 0.27f}, V3{0.06f, 0.065f, 0.08f}, py / float(size));
    }
    const V3 p = eye + rh.ray.tfar * dir;
    const V3 view = -1.0f * dir;
    V3 ng = normalize(V3{rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z});
    if (dot(ng, view) < 0.0f) ng = -1.0f * ng;
    const float lit = occluded(p + 4e-4f * ng, key) ? 0.0f : 1.0f;
    if (rh.hit.geomID == mesh_id) {  // skin: interpolated normal, Lambert; dark under the fur
      const uint32_t* t = &mesh.indices[3 * size_t(rh.hit.primID)];
      const float w[3] = {1.0f - rh.hit.u - rh.hit.v, rh.hit.u, rh.hit.v};
      V3 n;
      for (int k = 0; k < 3; ++k) n = n + w[k] * creature::at3(mesh.normals, t[k]);
      n = normalize(n);
      float uv[2];
      mesh.uv_at(rh.hit.primID, rh.hit.u, rh.hit.v, uv);
      const V3 albedo = lerp(V3{0.50f, 0.44f, 0.42f}, V3{0.10f, 0.06f, 0.035f}, density.bilinear(uv[0], uv[1]));
      const float light = 0.25f + 0.45f * std::max(dot(n, view), 0.0f) + 0.75f * lit * std::max(dot(n, key), 0.0f);
      return light * albedo;
    }
    // Fur: Kajiya-Kay with the strand tangent, dark at the root, light at the tip.
    float P[4], dPdu[4];
    rtcInterpolate1(curves, rh.hit.primID, rh.hit.u, rh.hit.v, RTC_BUFFER_TYPE_VERTEX, 0, P, dPdu, nullptr, 4);
    const V3 tangent = normalize(V3{dPdu[0], dPdu[1], dPdu[2]});
    const float along = (float(rh.hit.primID % segments_per_curve) + rh.hit.u) / float(segments_per_curve);
    const float tone = 0.75f + 0.5f * hash01(rh.hit.primID / segments_per_curve, 0x51u);  // per hair
    const V3 base = tone * lerp(V3{0.06f, 0.03f, 0.012f}, V3{0.50f, 0.29f, 0.12f}, std::sqrt(along));
    auto kajiya_kay = [&](V3 l, float weight) {
      const float tl = dot(tangent, l);
      const float diffuse = std::sqrt(std::max(0.0f, 1.0f - tl * tl));
      const V3 h = normalize(l + view);
      const float th = dot(tangent, h);
      const float spec = std::pow(std::sqrt(std::max(0.0f, 1.0f - th * th)), 60.0f);
      return weight * diffuse * base + (0.18f * weight * spec) * V3{1.0f, 0.92f, 0.8f};
    };
    return 0.18f * base + kajiya_kay(view, 0.35f) + kajiya_kay(key, 1.0f * lit);
  }
};

uint8_t encode(float linear) {
  const float s = std::pow(std::clamp(linear, 0.0f, 1.0f), 1.0f / 2.2f);
  return uint8_t(std::lround(255.0f * s));
}

}  // namespace

int main(int argc, char** argv) try {
  const Options opt = parse(argc, argv);
  struct Row {
    const char* stage;
    double seconds;
    std::string note;
  };
  std::vector<Row> rows;
  char note[200];

  // 1. Load the mesh and the density map.
  creature::Stopwatch clock;
  creature::Mesh mesh = creature::load_obj(opt.obj);
  const creature::GrayImage density = creature::load_png_gray(opt.density);
  if (mesh.uvs.empty() || mesh.normals.empty()) throw std::runtime_error(opt.obj + ": needs vt and vn");
  std::snprintf(note, sizeof note, "%zu triangles, %dx%d density", mesh.triangle_count(), density.width,
                density.height);
  rows.push_back({"load", clock.seconds(), note});

  // 2. Stamp guide roots and render roots with the same density map.
  clock = {};
  PelageStampParams sp = pelage_stamp_params_defaults();
  sp.density = density.map();
  sp.black_scale = 0.5f;  // black = half-size triangles = a quarter of the hairs
  sp.target_count = opt.guides, sp.seed = 1;
  const std::vector<PelageRoot> guide_roots = creature::stamp(mesh, sp);
  sp.target_count = opt.roots, sp.seed = 2;
  PelageStampInfo info{};
  const std::vector<PelageRoot> roots = creature::stamp(mesh, sp, &info);
  const size_t n = roots.size();
  std::snprintf(note, sizeof note, "%zu guide roots + %zu render roots (disk radius %.5f)", guide_roots.size(), n,
                double(info.radius));
  rows.push_back({"stamp", clock.seconds(), note});

  // 3. Guides (a groom tool's job): 16 points, 0.05 long, combed toward -y.
  const uint32_t cvs = 16;
  const std::vector<float> guide_points = creature::combed_guides(mesh, guide_roots, cvs, 0.05f);
  const PelageGuidesDesc guides = creature::guides_desc(guide_roots, guide_points, cvs);

  // 4. Bind every render hair to its neighbour guides (once per groom).
  clock = {};
  PelageBindInfo bind_info{};
  PelageBindParams bind_params = pelage_bind_params_defaults();
  bind_params.run.thread_count = 0;  // all cores; the bindings are the same for any count
  const std::vector<PelageStrandBinding> bindings =
      creature::bind(mesh, guides, roots.data(), n, bind_params, &bind_info);
  std::snprintf(note, sizeof note, "%u orphans, guide spacing %.4f", bind_info.orphans,
                double(bind_info.mean_spacing));
  rows.push_back({"bind", clock.seconds(), note});

  // 5. Groom values per hair: widths, a little kink, clumps, bend.
  clock = {};
  PelageGroomMaps maps = pelage_groom_maps_defaults();
  maps.root_width.constant = 0.0016f;
  maps.tip_width.constant = 0.0003f;
  maps.kink_amplitude.constant = 0.03f;
  maps.kink_frequency.constant = 3.0f;
  maps.clump.constant = 0.25f;
  maps.bend.constant = 0.1f;
  maps.seed = 7;
  std::vector<PelageStrandGroom> grooms = creature::groom(mesh, maps, roots.data(), n);
  rows.push_back({"groom", clock.seconds(), "kink 0.03 x 3, clump 0.25, bend 0.1, width 0.0016 -> 0.0003"});

  // 6. Settle (once per groom): hairs that would enter the body at rest (in
  // the gaps between fingers) are turned out about their root.
  PelageExpandParams ep = pelage_expand_params_defaults();  // 16 points, pinned ends
  ep.points_per_strand = 16;
  ep.end_points = PELAGE_END_POINTS_PINNED;
  ep.orphan_length = bind_info.mean_guide_length;
  ep.run.thread_count = 0;  // all cores
  clock = {};
  const PelageSettleInfo settled = creature::settle(mesh, guides, roots.data(), bindings.data(), grooms.data(), n, ep);
  std::snprintf(note, sizeof note, "%u hairs lifted out of the body (%u turned, %u shortened, %u unresolved)",
                settled.lifted, settled.turned, settled.shortened, settled.unresolved);
  rows.push_back({"settle", clock.seconds(), note});
  clock = {};
  const creature::Groom fur(roots.data(), bindings.data(), grooms.data(), n);  // checked once, kept for every frame
  rows.push_back({"handle", clock.seconds(), "strand records checked and copied once (pelage_groom_new)"});

  // 7. Embree geometry sharing our buffers: every hair for the camera; for
  // shadows, a copy of the hairs with rank < N/2, widened by N / kept: k
  // hairs of width w N / k cover as much as N of width w (coverage
  // 1 - exp(-N w l / A) depends on N w alone).
  creature::Expander expander(ep);
  const size_t per = expander.points_per_curve(), segments = per - 3;
  std::vector<float> points(4 * per * n);  // the vertex buffer Embree reads
  const std::vector<uint32_t> indices = creature::segment_indices(n, per);
  std::vector<size_t> shadow_hairs;
  for (size_t i = 0; i < n; ++i) {
    if (roots[i].rank < n / 2) shadow_hairs.push_back(i);
  }
  const float widen = float(n) / float(shadow_hairs.size());
  std::vector<float> shadow_points(4 * per * shadow_hairs.size());
  const std::vector<uint32_t> shadow_indices = creature::segment_indices(shadow_hairs.size(), per);
  const auto copy_shadow_hairs = [&] {
    for (size_t k = 0; k < shadow_hairs.size(); ++k) {
      const float* from = &points[4 * per * shadow_hairs[k]];
      float* to = &shadow_points[4 * per * k];
      for (size_t j = 0; j < 4 * per; ++j) to[j] = j % 4 == 3 ? from[j] * widen : from[j];
    }
  };
  creature::Device device;
  RTCScene scene = rtcNewScene(device.device), shadow = rtcNewScene(device.device);
  const unsigned mesh_id = creature::attach_mesh(device.device, scene, mesh);
  const unsigned shadow_mesh_id = creature::attach_mesh(device.device, shadow, mesh);
  const unsigned curves_id =
      creature::attach_curves(device.device, scene, points.data(), per * n, indices.data(), indices.size());
  const unsigned shadow_curves_id =
      creature::attach_curves(device.device, shadow, shadow_points.data(), per * shadow_hairs.size(),
                              shadow_indices.data(), shadow_indices.size());
  device.check("geometry");

  // 8. A frame's work once guides are posed (here: the rest pose): the
  // frame prepared once (mesh, tangents, guides in their root frames), then
  // the hairs expanded from it (a renderer would expand patch ranges).
  std::vector<double> frame_s;
  for (int f = 0; f < opt.frames; ++f) {
    clock = {};
    const creature::Frame frame(mesh, guides, ep);
    expander.expand(frame, fur, 0, n, points.data(), per * n);
    frame_s.push_back(clock.seconds());
  }
  std::sort(frame_s.begin(), frame_s.end());
  const double expand_s = frame_s[frame_s.size() / 2];
  std::snprintf(note, sizeof note, "%.2f frames/s: %zu curves x %zu points (median of %d)", 1.0 / expand_s, n, per,
                opt.frames);
  rows.push_back({"expand", expand_s, note});
  if (const size_t bad = creature::count_bad_points(points.data(), per * n)) {
    throw std::runtime_error(std::to_string(bad) + " control points are non-finite or have a negative radius");
  }
  copy_shadow_hairs();

  // 9. BVHs: the camera scene and the half-density shadow scene.
  clock = {};
  rtcCommitScene(scene);
  rtcCommitScene(shadow);
  device.check("scene build");
  std::snprintf(note, sizeof note, "%zu segments; shadows: %zu hairs (rank < N/2, %.2fx wide), %zu segments",
                indices.size(), shadow_hairs.size(), double(widen), shadow_indices.size());
  rows.push_back({"BVH", clock.seconds(), note});

  // 10. Render: a pinhole camera, `spp` stratified samples per pixel.
  clock = {};
  Renderer r{scene, shadow, mesh, density, mesh_id, rtcGetGeometry(scene, curves_id), unsigned(segments),
             {}, {}, {}, {}, 0.0f};
  r.eye = V3{1.55f, 0.75f, 3.55f};
  r.forward = normalize(V3{0.0f, 0.02f, 0.0f} - r.eye);
  r.right = normalize(cross(r.forward, V3{0.0f, 1.0f, 0.0f}));
  r.up = cross(r.right, r.forward);
  r.tan_half_fov = std::tan(0.5f * 36.0f * 3.14159265f / 180.0f);
  // an image of `size` pixels a side, `side`^2 stratified samples per pixel
  auto render = [&r](int size, int side) {
    std::vector<uint8_t> rgb(size_t(size) * size_t(size) * 3);
    tbb::parallel_for(tbb::blocked_range<int>(0, size), [&](const tbb::blocked_range<int>& range) {
      for (int y = range.begin(); y < range.end(); ++y) {
        for (int x = 0; x < size; ++x) {
          V3 sum;
          const uint32_t pixel = uint32_t(y) * uint32_t(size) + uint32_t(x);
          for (int s = 0; s < side * side; ++s) {
            const float jx = (float(s % side) + hash01(pixel, 2 * s)) / float(side);
            const float jy = (float(s / side) + hash01(pixel, 2 * s + 1)) / float(side);
            sum = sum + r.shade(float(x) + jx, float(y) + jy, size);
          }
          const V3 c = (1.0f / float(side * side)) * sum;
          uint8_t* out = &rgb[3 * size_t(pixel)];
          out[0] = encode(c.x), out[1] = encode(c.y), out[2] = encode(c.z);
        }
      }
    });
    return rgb;
  };
  const int size = opt.size, side = std::max(1, int(std::lround(std::sqrt(double(opt.spp)))));
  const std::vector<uint8_t> rgb = render(size, side);
  device.check("render");
  std::snprintf(note, sizeof note, "%dx%d, %d spp + shadow rays", size, size, side * side);
  rows.push_back({"render", clock.seconds(), note});

  // 11. Dynamics: the guides simulated while the upper body shakes; the fur
  // expanded from them each frame into the same Embree buffers.
  std::vector<double> sim_s, fur_s;
  const int tile = std::max(64, size / 4);
  std::vector<uint8_t> strip(size_t(tile) * size_t(tile) * 3 * size_t(opt.strip));
  if (opt.strip > 0) {
    clock = {};
    const PelageMeshDesc rest_desc = mesh.desc();
    PelageSimParams simp = pelage_sim_params_defaults();
    simp.link_radius = 1.5f * bind_info.mean_spacing;
    size_t sim_bytes = 0;
    creature::check(pelage_sim_size(&rest_desc, guide_roots.size(), &simp, &sim_bytes), "pelage_sim_size");
    std::vector<unsigned char> sim_memory(sim_bytes);
    PelageSim sim = nullptr;
    const PelageRestPose rest_pose{&rest_desc, &guides};
    creature::check(pelage_sim_new(&rest_pose, &simp, PelageArena{sim_memory.data(), sim_bytes}, &sim), "pelage_sim_new");
    const std::vector<float> rest_positions = mesh.positions;
    PelageColliders colliders{};
    colliders.body = 1;
    const int steps_per_tile = 3;
    for (int f = 0; f < opt.strip * steps_per_tile; ++f) {
      // a shake of the upper body, growing with height (a bend, not a rigid motion)
      const float t = float(f) / 24.0f, shake = 0.15f * std::sin(6.2831853f * 1.5f * t);
      for (size_t v = 0; v < mesh.vertex_count(); ++v) {
        const float up = std::max(rest_positions[3 * v + 1], 0.0f);
        mesh.positions[3 * v] = rest_positions[3 * v] + shake * up * up;
      }
      creature::Stopwatch step_clock;
      const creature::Frame frame(mesh, guides, ep);
      PelageStepParams step = pelage_step_params_defaults();
      step.colliders = &colliders;
      creature::check(pelage_sim_step(sim, frame.get(), &step, nullptr), "pelage_sim_step");
      creature::check(pelage_frame_set_sim_guides(frame.get(), sim, PelageRun{0, nullptr, nullptr}), "pelage_frame_set_sim_guides");
      sim_s.push_back(step_clock.seconds());
      step_clock = {};
      expander.expand(frame, fur, 0, n, points.data(), per * n);
      fur_s.push_back(step_clock.seconds());
      if (f % steps_per_tile != steps_per_tile - 1) continue;
      copy_shadow_hairs();
      for (auto [sc, geom] : {std::pair{scene, mesh_id}, {scene, curves_id}, {shadow, shadow_mesh_id},
                              {shadow, shadow_curves_id}}) {
        RTCGeometry g = rtcGetGeometry(sc, geom);
        rtcUpdateGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0);
        rtcCommitGeometry(g);
      }
      rtcCommitScene(scene);
      rtcCommitScene(shadow);
      const std::vector<uint8_t> frame_rgb = render(tile, 1);
      const int k = f / steps_per_tile;
      for (int y = 0; y < tile; ++y) {
        std::memcpy(&strip[(size_t(y) * size_t(tile) * size_t(opt.strip) + size_t(k) * size_t(tile)) * 3],
                    &frame_rgb[size_t(y) * size_t(tile) * 3], size_t(tile) * 3);
      }
    }
    device.check("strip");
    pelage_sim_free(sim);
    if (const size_t bad = creature::count_bad_points(points.data(), per * n)) {
      throw std::runtime_error(std::to_string(bad) + " simulated control points are non-finite");
    }
    const std::string strip_path = opt.out.substr(0, opt.out.rfind('.')) + "_strip.png";
    creature::write_png_rgb(strip_path, tile * opt.strip, tile, strip);
    std::sort(sim_s.begin(), sim_s.end());
    std::sort(fur_s.begin(), fur_s.end());
    std::snprintf(note, sizeof note, "%d frames: sim step %.1f ms, expand %.1f ms (medians); %s", opt.strip * steps_per_tile,
                  1e3 * sim_s[sim_s.size() / 2], 1e3 * fur_s[fur_s.size() / 2], strip_path.c_str());
    rows.push_back({"dynamics", clock.seconds(), note});
  }
  rtcReleaseScene(scene);
  rtcReleaseScene(shadow);

  // 12. Write the image.
  clock = {};
  creature::write_png_rgb(opt.out, size, size, rgb);
  rows.push_back({"write", clock.seconds(), opt.out});

  std::printf("pelage %u.%u.%u creature demo\n", PELAGE_VERSION_MAJOR, PELAGE_VERSION_MINOR, PELAGE_VERSION_PATCH);
  std::printf("bind: %u orphans of %zu hairs; mean guide length %.4f, mean guide spacing %.4f\n\n", bind_info.orphans,
              n, double(bind_info.mean_guide_length), double(bind_info.mean_spacing));
  std::printf("%-8s %9s  %s\n", "stage", "seconds", "");
  double total = 0.0;
  for (const Row& row : rows) {
    std::printf("%-8s %9.3f  %s\n", row.stage, row.seconds, row.note.c_str());
    total += row.seconds;
  }
  std::printf("%-8s %9.3f  (expand counted once)\n", "total", total);
  return EXIT_SUCCESS;
} catch (const std::exception& e) {
  std::fprintf(stderr, "demo: %s\n", e.what());
  return EXIT_FAILURE;
}

// demo.cpp: pelage's creature demo.
//
// Loads the creature mesh and its density map, stamps ~1,000,000 Poisson hair
// roots with pelage, grows a combed strand from each, hands the strands to
// Embree as round Catmull-Rom curves, and renders fur.png.
//
//   demo [creature.obj] [creature_density.png] [fur.png] [--roots N] [--size PIXELS] [--spp SAMPLES]
#include "creature_io.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#ifndef PELAGE_ASSETS_DIR
#define PELAGE_ASSETS_DIR "assets"
#endif

namespace {

struct V3 {
  float x = 0, y = 0, z = 0;
};
V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
V3 operator*(float s, V3 a) { return {s * a.x, s * a.y, s * a.z}; }
float dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
V3 cross(V3 a, V3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
V3 normalize(V3 a) { return (1.0f / std::sqrt(std::max(dot(a, a), 1e-30f))) * a; }
V3 lerp(V3 a, V3 b, float t) { return (1.0f - t) * a + t * b; }

struct Options {
  std::string obj = PELAGE_ASSETS_DIR "/creature.obj";
  std::string density = PELAGE_ASSETS_DIR "/creature_density.png";
  std::string out = "fur.png";
  uint32_t roots = 1000000;
  int size = 1024;
  int spp = 4;  // samples per pixel, a square number
};

Options parse(int argc, char** argv) {
  Options o;
  int positional = 0;
  for (int i = 1; i < argc; ++i) {
    const bool has_value = i + 1 < argc;
    if (!std::strcmp(argv[i], "--roots") && has_value) {
      o.roots = uint32_t(std::strtoul(argv[++i], nullptr, 10));
    } else if (!std::strcmp(argv[i], "--size") && has_value) {
      o.size = std::atoi(argv[++i]);
    } else if (!std::strcmp(argv[i], "--spp") && has_value) {
      o.spp = std::atoi(argv[++i]);
    } else if (argv[i][0] != '-' && positional < 3) {
      std::string* slots[3] = {&o.obj, &o.density, &o.out};
      *slots[positional++] = argv[i];
    } else {
      throw std::runtime_error(std::string("unknown argument ") + argv[i] +
                               "\nusage: demo [obj] [density.png] [out.png] [--roots N] [--size PIXELS] [--spp N]");
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
  RTCScene scene;
  const creature::Mesh& mesh;
  unsigned mesh_id;
  RTCGeometry curves;
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
    rtcOccluded1(scene, &ctx, &ray);
    return ray.tfar < 0.0f;
  }

  V3 shade(float px, float py, int size) const {
    const float sx = (2.0f * px / float(size) - 1.0f) * tan_half_fov;
    const float sy = (1.0f - 2.0f * py / float(size)) * tan_half_fov;
    const V3 dir = normalize(forward + sx * right + sy * up);
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh{};
    rh.ray.org_x = eye.x, rh.ray.org_y = eye.y, rh.ray.org_z = eye.z;
    rh.ray.dir_x = dir.x, rh.ray.dir_y = dir.y, rh.ray.dir_z = dir.z;
    rh.ray.tnear = 0.0f, rh.ray.tfar = 1e30f, rh.ray.mask = ~0u;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
      return lerp(V3{0.20f, 0.22f, 0.27f}, V3{0.06f, 0.065f, 0.08f}, py / float(size));
    }
    const V3 p = eye + rh.ray.tfar * dir;
    const V3 view = -1.0f * dir;
    V3 ng = normalize(V3{rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z});
    if (dot(ng, view) < 0.0f) ng = -1.0f * ng;
    const float lit = occluded(p + 4e-4f * ng, key) ? 0.0f : 1.0f;
    if (rh.hit.geomID == mesh_id) {  // skin: interpolated normal, Lambert
      const uint32_t* t = &mesh.indices[3 * size_t(rh.hit.primID)];
      const float w[3] = {1.0f - rh.hit.u - rh.hit.v, rh.hit.u, rh.hit.v};
      V3 n;
      for (int k = 0; k < 3; ++k) {
        const float* s = &mesh.normals[3 * size_t(t[k])];
        n = n + w[k] * V3{s[0], s[1], s[2]};
      }
      n = normalize(n);
      const float light = 0.25f + 0.45f * std::max(dot(n, view), 0.0f) + 0.75f * lit * std::max(dot(n, key), 0.0f);
      return light * V3{0.50f, 0.47f, 0.46f};
    }
    // Fur: Kajiya-Kay with the strand tangent, darker at the root.
    float P[4], dPdu[4];
    rtcInterpolate1(curves, rh.hit.primID, rh.hit.u, rh.hit.v, RTC_BUFFER_TYPE_VERTEX, 0, P, dPdu, nullptr, 4);
    const V3 tangent = normalize(V3{dPdu[0], dPdu[1], dPdu[2]});
    const V3 base = lerp(V3{0.07f, 0.035f, 0.015f}, V3{0.46f, 0.26f, 0.11f}, rh.hit.u);
    auto kajiya_kay = [&](V3 l, float weight) {
      const float tl = dot(tangent, l);
      const float diffuse = std::sqrt(std::max(0.0f, 1.0f - tl * tl));
      const V3 h = normalize(l + view);
      const float th = dot(tangent, h);
      const float spec = std::pow(std::sqrt(std::max(0.0f, 1.0f - th * th)), 60.0f);
      return weight * diffuse * base + (0.18f * weight * spec) * V3{1.0f, 0.92f, 0.8f};
    };
    return 0.15f * base + kajiya_kay(view, 0.35f) + kajiya_kay(key, 1.0f * lit);
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

  // 1. Load the mesh and the density map.
  creature::Stopwatch clock;
  const creature::Mesh mesh = creature::load_obj(opt.obj);
  const creature::GrayImage density = creature::load_png_gray(opt.density);
  if (mesh.uvs.empty() || mesh.normals.empty()) throw std::runtime_error(opt.obj + ": needs vt and vn");
  rows.push_back({"load", clock.seconds(),
                  std::to_string(mesh.triangle_count()) + " triangles, " + std::to_string(density.width) + "x" +
                      std::to_string(density.height) + " density"});

  // 2. Stamp: size the call, hand pelage an arena and a root buffer (scratch
  // memory: no need to zero it), then keep the roots it wrote.
  clock = {};
  const PelageMeshDesc desc = mesh.desc();
  PelageStampParams params = pelage_stamp_params_defaults();
  params.target_count = opt.roots;
  params.seed = 2024;
  params.density = density.map();
  params.black_scale = 0.5f;  // black = half-size triangles = a quarter of the hairs
  size_t arena_bytes = 0, max_roots = 0;
  creature::check(pelage_stamp_query(&desc, &params, &arena_bytes, &max_roots), "pelage_stamp_query");
  std::unique_ptr<unsigned char[]> arena(new unsigned char[arena_bytes]);
  std::unique_ptr<PelageRoot[]> buffer(new PelageRoot[max_roots]);
  char note[160];
  std::snprintf(note, sizeof note, "arena %.0f MB, root buffer %.0f MB (%zu roots)", double(arena_bytes) / 1e6,
                double(max_roots * sizeof(PelageRoot)) / 1e6, max_roots);
  rows.push_back({"query", clock.seconds(), note});

  clock = {};
  size_t count = 0;
  PelageStampInfo info{};
  creature::check(pelage_stamp(&desc, &params, arena.get(), arena_bytes, buffer.get(), max_roots, &count, &info),
                  "pelage_stamp");
  const double stamp_s = clock.seconds();
  std::snprintf(note, sizeof note, "%zu roots, %.2f M roots/s", count, double(count) / stamp_s * 1e-6);
  rows.push_back({"stamp", stamp_s, note});
  const std::vector<PelageRoot> roots(buffer.get(), buffer.get() + count);
  arena.reset();
  buffer.reset();

  // 3. Root positions and normals on the mesh.
  clock = {};
  std::vector<float> positions, normals;
  creature::evaluate(mesh, roots, positions, normals);
  rows.push_back({"evaluate", clock.seconds(), ""});

  // 4. Strands: combed down, bending from 45 to 75 degrees, tapering.
  clock = {};
  creature::StrandParams sp;
  sp.length = 0.05f;
  sp.root_radius = 0.0008f;
  sp.tip_radius = 0.0002f;
  sp.tilt_root_deg = 45.0f;
  sp.tilt_tip_deg = 75.0f;
  const creature::Strands strands = creature::grow_strands(positions, normals, sp);
  if (const size_t bad = creature::count_bad_control_points(strands)) {
    throw std::runtime_error(std::to_string(bad) + " control points are non-finite or have a negative radius");
  }
  rows.push_back({"strands", clock.seconds(), std::to_string(strands.count()) + " curves x 4 control points"});

  // 5. Embree scene: the skin and the fur.
  clock = {};
  creature::Device device;
  RTCScene scene = rtcNewScene(device.device);
  const unsigned mesh_id = creature::attach_mesh(device.device, scene, mesh);
  const unsigned curves_id = creature::attach_strands(device.device, scene, strands);
  rtcCommitScene(scene);
  device.check("scene build");
  rows.push_back({"BVH build", clock.seconds(), ""});

  // 6. Render: a pinhole camera, `spp` stratified samples per pixel.
  clock = {};
  Renderer r{scene, mesh, mesh_id, rtcGetGeometry(scene, curves_id), {}, {}, {}, {}, 0.0f};
  r.eye = V3{1.55f, 0.75f, 3.55f};
  r.forward = normalize(V3{0.0f, 0.02f, 0.0f} - r.eye);
  r.right = normalize(cross(r.forward, V3{0.0f, 1.0f, 0.0f}));
  r.up = cross(r.right, r.forward);
  r.tan_half_fov = std::tan(0.5f * 36.0f * 3.14159265f / 180.0f);
  const int size = opt.size, side = std::max(1, int(std::lround(std::sqrt(double(opt.spp)))));
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
  device.check("render");
  rows.push_back({"render", clock.seconds(),
                  std::to_string(size) + "x" + std::to_string(size) + ", " + std::to_string(side * side) +
                      " spp + shadow rays"});
  rtcReleaseScene(scene);

  // 7. Write the image.
  clock = {};
  creature::write_png_rgb(opt.out, size, size, rgb);
  rows.push_back({"write", clock.seconds(), opt.out});

  std::printf("pelage %u.%u.%u creature demo\n", PELAGE_VERSION_MAJOR, PELAGE_VERSION_MINOR, PELAGE_VERSION_PATCH);
  std::printf("stamp: target %u, got %zu roots; disk radius %.5f, %u passes, %u candidates, %u pruned, "
              "%u degenerate triangles\n",
              params.target_count, count, info.radius, info.passes, info.candidates, info.pruned,
              info.degenerate_triangles);
  std::printf("\n");
  std::printf("%-10s %10s  %s\n", "stage", "seconds", "");
  double total = 0.0;
  for (const Row& row : rows) {
    std::printf("%-10s %10.3f  %s\n", row.stage, row.seconds, row.note.c_str());
    total += row.seconds;
  }
  std::printf("%-10s %10.3f\n", "total", total);
  return EXIT_SUCCESS;
} catch (const std::exception& e) {
  std::fprintf(stderr, "demo: %s\n", e.what());
  return EXIT_FAILURE;
}

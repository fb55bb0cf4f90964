// A shot on a render farm (paper 3.3, 4), one subcommand per kind of job:
//
//   shot sim <creature.obj> <dir> <frames> [hairs]      the simulation pass, frame after frame:
//       the groom file (once per asset), then per frame the guides simulated
//       over the shutter (frame_NNNN.pguide, two samples), the deformed mesh
//       (frame_NNNN.mesh) and where the guides meet the shirt (trim records)
//   shot reduce <dir> <frames>                          the shot pass: every frame's trim
//       records into one length per hair (shot.ptriml)
//   shot render <dir> <first> <count>                   frames first .. first + count - 1,
//       each from its own files (and the groom file and shot.ptriml) alone,
//       all the fur expanded into one motion-blurred Embree scene: frame_NNNN.png
//   shot local <creature.obj> <dir> <frames> [hairs]    the three in one process
//
// farm/shot.sh submits sim, reduce and a job array of renders to Slurm. The
// frames must have the same bits however they are split into tasks and at
// any thread count: the farm_slurm test compares them with `shot local`.
#include <embree3/rtcore.h>
#include <pelage.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "creature_io.h"

using creature::check;
using creature::V3;

namespace {

const uint32_t kGuides = 4000, kCvs = 16, kPatchSize = 1000;
const float kGuideLength = 0.05f, kFps = 24.0f;
// The shirt sits closer to the skin than the hairs reach, so they cross it.
const float kShirtGap = 0.6f * kGuideLength;
// Shutter samples: the frame's time and half a frame later (a 180 degree
// shutter), each one simulation step.
const int kSamples = 2;
const int kImageSize = 512;

std::string frame_path(const std::string& dir, int frame, const std::string& suffix) {
  char name[16];
  std::snprintf(name, sizeof name, "/frame_%04d", frame);
  return dir + name + suffix;
}

// The creature at time t (seconds): the upper body sways along x, a function
// of time alone, as an animation cache would give it. Normals (the shirt and
// the root frames use them) follow the shear x += s(y) by its inverse transpose.
creature::Mesh posed(const creature::Mesh& rest, float t) {
  const float a = 0.12f * std::sin(6.2831853f * 1.5f * t);
  creature::Mesh m = rest;
  for (size_t v = 0; v < m.vertex_count(); ++v) {
    const float y = std::max(m.positions[3 * v + 1], 0.0f);
    m.positions[3 * v] += a * y * y;
    float* n = &m.normals[3 * v];
    n[1] -= 2.0f * a * y * n[0];
    const float len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int k = 0; k < 3; ++k) n[k] /= len;
  }
  return m;
}

// A frame's deformed mesh at each shutter sample, the renderer's animation
// cache: vertex and triangle counts (uint32), the triangles, then each
// sample's positions and normals (float32, little-endian like every machine
// we render on).
void write_meshes(const std::string& path, const std::vector<creature::Mesh>& samples) {
  const uint32_t counts[2] = {uint32_t(samples[0].vertex_count()), uint32_t(samples[0].triangle_count())};
  std::ofstream out(path, std::ios::binary);
  const auto put = [&](const auto& v) {
    out.write(reinterpret_cast<const char*>(v.data()), std::streamsize(4 * v.size()));
  };
  out.write(reinterpret_cast<const char*>(counts), sizeof counts);
  put(samples[0].indices);
  for (const creature::Mesh& m : samples) put(m.positions), put(m.normals);
  if (!out) throw std::runtime_error("cannot write " + path);
}

std::vector<creature::Mesh> read_meshes(const std::string& path) {
  const std::vector<unsigned char> bytes = creature::read_file(path);
  uint32_t counts[2] = {};
  if (bytes.size() >= sizeof counts) std::memcpy(counts, bytes.data(), sizeof counts);
  if (bytes.size() != sizeof counts + 12 * size_t(counts[1]) + kSamples * 24 * size_t(counts[0])) {
    throw std::runtime_error(path + ": not a mesh file of " + std::to_string(kSamples) + " samples");
  }
  size_t at = sizeof counts;
  const auto take = [&](auto& v, size_t count) {
    v.resize(count);
    std::memcpy(v.data(), &bytes[at], 4 * count);
    at += 4 * count;
  };
  std::vector<creature::Mesh> samples(kSamples);
  take(samples[0].indices, 3 * size_t(counts[1]));
  for (creature::Mesh& m : samples) {
    m.indices = samples[0].indices;
    take(m.positions, 3 * size_t(counts[0]));
    take(m.normals, 3 * size_t(counts[0]));
  }
  return samples;
}

// What every job reads first: the groom file's guide set (the neutral pose
// the caches are coded against) and its strands as a groom.
struct Asset {
  PelageGroomFileInfo info{};
  std::vector<PelageRoot> guide_roots;
  std::vector<float> guide_points;
  std::unique_ptr<creature::Groom> groom;

  explicit Asset(const std::string& path) {
    const std::vector<unsigned char> file = creature::read_file(path);
    check(pelage_groom_file_info(file.data(), file.size(), &info), "pelage_groom_file_info");
    const size_t n = info.strand_count;
    guide_roots.resize(info.guide_count);
    guide_points.resize(info.guide_count * info.points_per_guide * 3);
    std::vector<PelageRoot> roots(n);
    std::vector<PelageStrandBinding> bindings(n);
    std::vector<PelageStrandGroom> grooms(n);
    std::vector<PelagePatch> patches(info.patch_count);
    const PelageGroomFileBuffers out{guide_roots.data(), guide_points.data(), info.guide_count, roots.data(),
                                     bindings.data(),    grooms.data(),       n,                patches.data(),
                                     info.patch_count};
    check(pelage_groom_file_read(file.data(), file.size(), &out), "pelage_groom_file_read");
    groom = std::make_unique<creature::Groom>(roots.data(), bindings.data(), grooms.data(), n);
  }
  PelageGuideSet set() const {
    return {guide_roots.data(), guide_points.data(), info.guide_count, info.points_per_guide, info.id};
  }
};

using FramePtr = std::unique_ptr<PelageFrameTy, void (*)(PelageFrame)>;

// --- The simulation pass ----------------------------------------------------

// The shirt on the deformed body: its torso pushed kShirtGap out along the
// skin's normals, so it moves with the body.
creature::Mesh shirt(const creature::Mesh& body) {
  creature::Mesh cloth;
  cloth.positions = body.positions;
  for (size_t i = 0; i < cloth.positions.size(); ++i) cloth.positions[i] += kShirtGap * body.normals[i];
  const auto torso = [&](uint32_t v) {
    const float y = body.positions[3 * v + 1];
    return y > -0.25f && y < 0.2f;
  };
  for (size_t t = 0; t < body.indices.size(); t += 3) {
    if (std::all_of(&body.indices[t], &body.indices[t + 3], torso)) {
      cloth.indices.insert(cloth.indices.end(), &body.indices[t], &body.indices[t + 3]);
    }
  }
  return cloth;
}

// Where each posed guide of `frame` first meets the shirt or the body, as
// a trim records file for the shot pass. Returns the guides that meet one.
size_t write_trim_records(const std::string& path, PelageFrame frame, const creature::Mesh& body,
                          const PelageColliders& colliders, size_t guides) {
  const creature::Mesh cloth = shirt(body);
  const PelageMeshDesc cloth_desc = cloth.desc();
  std::vector<PelageTrimRecord> records(guides);
  size_t count = 0, bytes = 0;
  check(pelage_trim_find(frame, &cloth_desc, &colliders, PelageRun{0, nullptr, nullptr}, records.data(), records.size(), &count),
        "pelage_trim_find");
  check(pelage_trim_records_size(count, &bytes), "pelage_trim_records_size");
  std::vector<unsigned char> file(bytes);
  check(pelage_trim_records_write(records.data(), count, guides, kCvs, file.data(), bytes, &bytes),
        "pelage_trim_records_write");
  creature::write_file(path, file.data(), bytes);
  return count;
}

// Trim records per shutter sample: the shot pass keeps each hair's
// shortest length over both, so the shirt holds over the whole shutter.
std::string records_path(const std::string& dir, int frame, int sample) {
  return frame_path(dir, frame, "_s" + std::to_string(sample) + ".ptrimr");
}

void simulate(const std::string& obj, const std::string& dir, int frames, uint32_t hairs) {
  creature::Stopwatch clock;
  const creature::Mesh rest = creature::load_obj(obj);
  if (rest.normals.empty()) throw std::runtime_error(obj + ": the shot needs vertex normals");
  PelageStampParams sp = pelage_stamp_params_defaults();
  sp.target_count = kGuides, sp.seed = 1;
  const std::vector<PelageRoot> guide_roots = creature::stamp(rest, sp);
  const std::vector<float> rest_points = creature::combed_guides(rest, guide_roots, kCvs, kGuideLength);
  const std::vector<unsigned char> groom = creature::groom_file(rest, guide_roots, rest_points, kCvs, hairs, kPatchSize);
  creature::write_file(dir + "/creature.pgroom", groom.data(), groom.size());
  const Asset asset(dir + "/creature.pgroom");
  const PelageGuideSet set = asset.set();
  std::printf("sim: groom file, %zu hairs on %zu guides: %.2f s\n", asset.info.strand_count, guide_roots.size(),
              clock.seconds());

  const PelageMeshDesc rest_desc = rest.desc();
  const PelageGuidesDesc rest_guides = creature::guides_desc(guide_roots, rest_points, kCvs);
  PelageSimParams params = pelage_sim_params_defaults();
  params.link_radius = 0.05f;
  size_t bytes = 0;
  check(pelage_sim_size(&rest_desc, guide_roots.size(), &params, &bytes), "pelage_sim_size");
  std::vector<unsigned char> memory(bytes);
  PelageSim raw = nullptr;
  const PelageRestPose rest_pose{&rest_desc, &rest_guides};
  check(pelage_sim_new(&rest_pose, &params, PelageArena{memory.data(), bytes}, &raw), "pelage_sim_new");
  const std::unique_ptr<PelageSimTy, void (*)(PelageSim)> sim(raw, pelage_sim_free);
  PelageColliders colliders{};
  colliders.body = 1;
  PelageExpandParams ep = pelage_expand_params_defaults();
  ep.points_per_strand = kCvs;

  check(pelage_guide_cache_size(set.guide_count, kCvs, kSamples, 0, &bytes), "pelage_guide_cache_size");
  std::vector<unsigned char> cache(bytes);
  for (int f = 0; f < frames; ++f) {
    clock = {};
    std::vector<creature::Mesh> meshes;
    std::vector<std::unique_ptr<creature::Frame>> samples;
    size_t met = 0;
    for (int k = 0; k < kSamples; ++k) {
      meshes.push_back(posed(rest, (float(f) + float(k) / kSamples) / kFps));
      samples.push_back(std::make_unique<creature::Frame>(meshes[k], rest_guides, ep));
      const PelageFrame frame = samples[k]->get();
      PelageStepParams step = pelage_step_params_defaults();
      step.dt = 1.0f / (kFps * kSamples);
      step.colliders = &colliders;
      check(pelage_sim_step(sim.get(), frame, &step, nullptr), "pelage_sim_step");
      check(pelage_frame_set_sim_guides(frame, sim.get(), PelageRun{0, nullptr, nullptr}), "pelage_frame_set_sim_guides");
      met = std::max(met, write_trim_records(records_path(dir, f, k), frame, meshes[k], colliders, set.guide_count));
    }
    const PelageFrame at[kSamples] = {samples[0]->get(), samples[1]->get()};
    check(pelage_guide_cache_write(&set, at, kSamples, 0, PelageRun{1, nullptr, nullptr}, cache.data(), cache.size(), &bytes),
          "pelage_guide_cache_write");
    creature::write_file(frame_path(dir, f, ".pguide"), cache.data(), bytes);
    write_meshes(frame_path(dir, f, ".mesh"), meshes);
    std::printf("sim: frame %d: cache %.1f KB, up to %zu guides meet the shirt or the body: %.2f s\n", f,
                double(bytes) / 1e3, met, clock.seconds());
  }
}

// --- The shot pass ------------------------------------------------------------

void reduce(const std::string& dir, int frames) {
  const Asset asset(dir + "/creature.pgroom");
  std::vector<uint16_t> lengths(asset.info.strand_count, PELAGE_TRIM_WHOLE);
  for (int f = 0; f < frames; ++f) {
    for (int k = 0; k < kSamples; ++k) {
      const std::vector<unsigned char> file = creature::read_file(records_path(dir, f, k));
      PelageTrimRecordsInfo info{};
      check(pelage_trim_records_info(file.data(), file.size(), &info), "pelage_trim_records_info");
      std::vector<PelageTrimRecord> records(info.record_count);
      check(pelage_trim_records_read(file.data(), file.size(), records.data(), records.size(), &info),
            "pelage_trim_records_read");
      check(pelage_trim_shortest(asset.groom->get(), records.data(), records.size(), info.guide_count,
                                 info.points_per_guide, lengths.data(), lengths.size()),
            "pelage_trim_shortest");
    }
  }
  size_t bytes = 0;
  check(pelage_trim_lengths_size(lengths.size(), &bytes), "pelage_trim_lengths_size");
  std::vector<unsigned char> file(bytes);
  check(pelage_trim_lengths_write(lengths.data(), lengths.size(), file.data(), bytes, &bytes),
        "pelage_trim_lengths_write");
  creature::write_file(dir + "/shot.ptriml", file.data(), bytes);
  const auto cut = std::count_if(lengths.begin(), lengths.end(), [](uint16_t l) { return l < PELAGE_TRIM_WHOLE; });
  std::printf("reduce: %d frames: %td of %zu hairs trimmed, %zu bytes\n", frames, cut, lengths.size(), bytes);
}

// --- The render tasks ---------------------------------------------------------

// Round Catmull-Rom curves or triangles moving between the shutter samples:
// one vertex buffer per sample (Embree's time steps).
void attach_moving(RTCDevice device, RTCScene scene, RTCGeometryType type, const std::vector<float>* vertices,
                   RTCFormat format, size_t stride, const std::vector<uint32_t>& indices, RTCFormat index_format,
                   size_t index_stride) {
  RTCGeometry g = rtcNewGeometry(device, type);
  rtcSetGeometryTimeStepCount(g, kSamples);
  for (int k = 0; k < kSamples; ++k) {
    // copied: Embree reads vertices with 16-byte loads past a float3 buffer's end
    void* p = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, unsigned(k), format, stride,
                                      4 * vertices[k].size() / stride);
    if (p) std::memcpy(p, vertices[k].data(), 4 * vertices[k].size());
  }
  void* t = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, index_format, index_stride,
                                    4 * indices.size() / index_stride);
  if (t) std::memcpy(t, indices.data(), 4 * indices.size());
  rtcCommitGeometry(g);
  rtcAttachGeometry(scene, g);
  rtcReleaseGeometry(g);
}

// One ray per pixel at a time in the shutter hashed from the pixel, headlight
// shading: every pixel is a function of the scene alone, not of the threads.
// Skin grey, the shirt blue (a hair through it would show), fur brown.
std::vector<uint8_t> shade(RTCScene scene) {
  const V3 eye{1.6f, 0.8f, 3.6f}, forward = normalize(V3{0.0f, 0.05f, 0.0f} - eye);
  const V3 right = normalize(cross(forward, V3{0.0f, 1.0f, 0.0f})), up = cross(right, forward);
  const float fov_tan = 0.42f;
  std::vector<uint8_t> rgb(3 * size_t(kImageSize) * kImageSize);
  tbb::parallel_for(0, kImageSize, [&](int y) {
    for (int x = 0; x < kImageSize; ++x) {
      const float sx = (2.0f * (float(x) + 0.5f) / kImageSize - 1.0f) * fov_tan;
      const float sy = (1.0f - 2.0f * (float(y) + 0.5f) / kImageSize) * fov_tan;
      const V3 dir = normalize(forward + sx * right + sy * up);
      RTCIntersectContext ctx;
      rtcInitIntersectContext(&ctx);
      RTCRayHit rh{};
      rh.ray.org_x = eye.x, rh.ray.org_y = eye.y, rh.ray.org_z = eye.z;
      rh.ray.dir_x = dir.x, rh.ray.dir_y = dir.y, rh.ray.dir_z = dir.z;
      rh.ray.tfar = 1e30f, rh.ray.mask = ~0u, rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      rh.ray.time = float((uint32_t(x) * 73856093u ^ uint32_t(y) * 19349663u) % 1024u) / 1023.0f;
      rtcIntersect1(scene, &ctx, &rh);
      V3 c{0.12f, 0.13f, 0.16f};
      if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) {
        const float l = 0.2f + 0.8f * std::fabs(dot(normalize(V3{rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z}), dir));
        const V3 albedo[3] = {{0.55f, 0.5f, 0.48f}, {0.25f, 0.35f, 0.6f}, {0.45f, 0.3f, 0.18f}};
        c = l * albedo[std::min(rh.hit.geomID, 2u)];
      }
      uint8_t* px = &rgb[3 * (size_t(y) * kImageSize + size_t(x))];
      px[0] = uint8_t(255.0f * std::min(c.x, 1.0f)), px[1] = uint8_t(255.0f * std::min(c.y, 1.0f));
      px[2] = uint8_t(255.0f * std::min(c.z, 1.0f));
    }
  });
  return rgb;
}

void render_frame(const Asset& asset, const std::vector<uint16_t>& lengths, creature::Device& device,
                  const std::string& dir, int f) {
  creature::Stopwatch clock;
  const std::vector<creature::Mesh> meshes = read_meshes(frame_path(dir, f, ".mesh"));
  const std::vector<unsigned char> cache = creature::read_file(frame_path(dir, f, ".pguide"));
  const PelageGuideSet set = asset.set();
  PelageExpandParams ep = pelage_expand_params_defaults();
  ep.points_per_strand = asset.info.points_per_guide;
  ep.run.thread_count = 0;
  const creature::Expander expander(ep);
  const size_t n = asset.info.strand_count, per = expander.points_per_curve();
  const PelageStrandEdits edits{lengths.data(), nullptr};
  std::vector<float> points[kSamples];
  for (int k = 0; k < kSamples; ++k) {
    const PelageMeshDesc desc = meshes[k].desc();
    PelageFrame raw = nullptr;
    check(pelage_frame_new(&desc, set.guide_count, set.points_per_guide, &raw), "pelage_frame_new");
    const FramePtr frame(raw, pelage_frame_free);
    check(pelage_guide_cache_read(cache.data(), cache.size(), &set, uint32_t(k), frame.get(), PelageRun{0, nullptr, nullptr}),
          "pelage_guide_cache_read");
    points[k].resize(4 * per * n);
    const PelageCurves curves{points[k].data(), 16, per * n, nullptr, nullptr};
    check(pelage_groom_expand_edited(asset.groom->get(), frame.get(), 0, n, &edits, &ep, &curves),
          "pelage_groom_expand_edited");
  }
  const double expand_s = clock.seconds();
  // medium build quality: Embree builds the same BVH at any thread count
  // (not at RTC_BUILD_QUALITY_HIGH; RenderKit/embree#20)
  RTCScene scene = rtcNewScene(device.device);
  std::vector<float> skin[kSamples], cloth[kSamples];
  for (int k = 0; k < kSamples; ++k) skin[k] = meshes[k].positions, cloth[k] = shirt(meshes[k]).positions;
  attach_moving(device.device, scene, RTC_GEOMETRY_TYPE_TRIANGLE, skin, RTC_FORMAT_FLOAT3, 12, meshes[0].indices,
                RTC_FORMAT_UINT3, 12);
  attach_moving(device.device, scene, RTC_GEOMETRY_TYPE_TRIANGLE, cloth, RTC_FORMAT_FLOAT3, 12,
                shirt(meshes[0]).indices, RTC_FORMAT_UINT3, 12);
  attach_moving(device.device, scene, RTC_GEOMETRY_TYPE_ROUND_CATMULL_ROM_CURVE, points, RTC_FORMAT_FLOAT4, 16,
                creature::segment_indices(n, per), RTC_FORMAT_UINT, 4);
  rtcCommitScene(scene);
  device.check("scene");
  const double build_s = clock.seconds() - expand_s;
  const std::vector<uint8_t> rgb = shade(scene);
  rtcReleaseScene(scene);
  device.check("render");
  creature::write_png_rgb(frame_path(dir, f, ".png"), kImageSize, kImageSize, rgb);
  std::printf("render: frame %d: %zu hairs x %d samples expanded %.2f s, BVH %.2f s, rendered %.2f s\n", f, n,
              kSamples, expand_s, build_s, clock.seconds() - expand_s - build_s);
}

void render(const std::string& dir, int first, int count) {
  const Asset asset(dir + "/creature.pgroom");
  const std::vector<unsigned char> file = creature::read_file(dir + "/shot.ptriml");
  std::vector<uint16_t> lengths(asset.info.strand_count);
  size_t strands = 0;
  check(pelage_trim_lengths_read(file.data(), file.size(), lengths.data(), lengths.size(), &strands),
        "pelage_trim_lengths_read");
  if (strands != lengths.size()) throw std::runtime_error("shot.ptriml: the lengths of another groom");
  creature::Device device;
  for (int f = first; f < first + count; ++f) render_frame(asset, lengths, device, dir, f);
}

}  // namespace

int main(int argc, char** argv) try {
  const std::vector<std::string> a(argv + 1, argv + argc);
  const auto number = [&](size_t i) { return std::stoi(a.at(i)); };
  const auto hairs = [&](size_t i) { return a.size() > i ? uint32_t(std::stoul(a[i])) : 200000u; };
  if (a.size() >= 4 && (a[0] == "sim" || a[0] == "local")) {
    simulate(a[1], a[2], number(3), hairs(4));
    if (a[0] == "local") {
      reduce(a[2], number(3));
      render(a[2], 0, number(3));
    }
  } else if (a.size() == 3 && a[0] == "reduce") {
    reduce(a[1], number(2));
  } else if (a.size() == 4 && a[0] == "render") {
    render(a[1], number(2), number(3));
  } else {
    std::fprintf(stderr, "usage: shot sim|local <creature.obj> <dir> <frames> [hairs]\n"
                         "       shot reduce <dir> <frames>\n"
                         "       shot render <dir> <first frame> <count>\n");
    return 2;
  }
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "shot: %s\n", e.what());
  return 1;
}

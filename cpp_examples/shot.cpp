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
//   shot status <creature.obj> <dir> <frames> [hairs]   what is left to do: "sim done|todo",
//       "reduce done|todo", "render" and the frames without a good image
//
// farm/shot.sh submits sim, reduce and a job array of renders to Slurm. The
// frames must have the same bits however they are split into tasks and at
// any thread count: the farm_slurm test compares them with `shot local`.
// Every job may be killed and rerun (farm_faults): each file is written
// whole or not at all and sealed with the shot's identity, its frame and its
// sample (farm_files.h), and a job skips the files that are already good.
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
#include "farm_files.h"

using creature::check;
using creature::V3;
using farm::Kind;
using farm::kEvery;

namespace {

const uint32_t kGuides = 4000, kCvs = 16, kPatchSize = 1000;
const float kGuideLength = 0.05f, kFps = 24.0f;
// The shirt sits closer to the skin than the hairs reach, so they cross it.
const float kShirtGap = 0.6f * kGuideLength;
// Shutter samples: the frame's time and half a frame later (a 180 degree
// shutter), each one simulation step.
const int kSamples = 2;
const int kImageSize = 512;
// Part of the shot's identity: bump it with any change to this tool that
// changes its files' bits, so a shot folder's older files are not taken as good.
const uint32_t kRecipe = 1;

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
// cache, framed like pelage's files (docs/FORMAT.md, "Deformed mesh"):
// vertex, triangle and sample counts, then the triangles and each sample's
// positions and normals (float32, little-endian like every machine we render on).
const char kMeshMagic[] = "PLMESH\0";
std::vector<unsigned char> mesh_file(const std::vector<creature::Mesh>& samples) {
  std::vector<unsigned char> payload;
  const auto put = [&](const auto& v) {
    const auto* p = reinterpret_cast<const unsigned char*>(v.data());
    payload.insert(payload.end(), p, p + 4 * v.size());
  };
  put(samples[0].indices);
  for (const creature::Mesh& m : samples) put(m.positions), put(m.normals);
  return farm::frame_bytes(kMeshMagic, 1, {samples[0].vertex_count(), samples[0].triangle_count(), samples.size()},
                           payload.data(), payload.size());
}

std::vector<creature::Mesh> read_meshes(const std::string& path, const std::vector<unsigned char>& bytes) {
  const farm::Framed f = farm::unframe(path, bytes, kMeshMagic, 1, 3);
  const uint64_t vertices = f.fields[0], triangles = f.fields[1];
  if (f.fields[2] != kSamples || vertices == 0 || triangles == 0 || vertices >= UINT32_MAX ||
      triangles >= UINT32_MAX || f.size != 12 * triangles + kSamples * 24 * vertices) {
    throw std::runtime_error(path + ": not a mesh file of " + std::to_string(kSamples) + " samples");
  }
  size_t at = 0;
  const auto take = [&](auto& v, size_t count) {
    v.resize(count);
    std::memcpy(v.data(), f.payload + at, 4 * count);
    at += 4 * count;
  };
  std::vector<creature::Mesh> samples(kSamples);
  take(samples[0].indices, 3 * size_t(triangles));
  for (creature::Mesh& m : samples) {
    m.indices = samples[0].indices;
    take(m.positions, 3 * size_t(vertices));
    take(m.normals, 3 * size_t(vertices));
    for (float x : m.positions) {
      if (!std::isfinite(x)) throw std::runtime_error(path + ": a position that is not finite");
    }
  }
  for (uint32_t i : samples[0].indices) {
    if (i >= vertices) throw std::runtime_error(path + ": a triangle names a vertex past the mesh");
  }
  return samples;
}

// Everything a frame's bits depend on besides the code: the creature's
// bytes, the hair and frame counts, the tool's settings and pelage's version.
farm::Identity shot_identity(const std::string& obj, uint32_t hairs, int frames) {
  if (frames < 1) throw std::runtime_error("a shot has at least one frame");
  const std::vector<unsigned char> bytes = creature::read_file(obj);
  const uint32_t settings[] = {kRecipe,    pelage_version(), hairs,    uint32_t(frames), kGuides,
                               kCvs,       kPatchSize,       kSamples, kImageSize};
  const float scene[] = {kGuideLength, kShirtGap, kFps};
  const uint64_t hash = farm::fnv1a(scene, sizeof scene, farm::fnv1a(settings, sizeof settings));
  return {farm::fnv1a(bytes.data(), bytes.size(), hash), uint32_t(frames)};
}

void write_sealed(const std::string& path, const farm::Identity& id, Kind kind, uint32_t frame, uint32_t sample,
                  const unsigned char* data, size_t size) {
  const std::vector<unsigned char> file = farm::seal(id, kind, frame, sample, data, size);
  farm::write_atomic(path, file.data(), file.size());
}

// What every job reads first: the groom file's guide set (the neutral pose
// the caches are coded against) and its strands as a groom.
struct Asset {
  PelageGroomFileInfo info{};
  std::vector<PelageRoot> guide_roots;
  std::vector<float> guide_points;
  std::unique_ptr<creature::Groom> groom;

  farm::Identity id;

  // The groom file at `path`: its seal names the shot every other file must belong to.
  explicit Asset(const std::string& path) : Asset(farm::unseal(path, Kind::Groom)) {}
  explicit Asset(const farm::Sealed& sealed) : id(sealed.id) {
    const std::vector<unsigned char>& file = sealed.file;
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
size_t write_trim_records(const std::string& path, const farm::Identity& id, int f, int k, PelageFrame frame,
                          const creature::Mesh& body, const PelageColliders& colliders, size_t guides) {
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
  write_sealed(path, id, Kind::TrimRecords, uint32_t(f), uint32_t(k), file.data(), bytes);
  return count;
}

// Trim records per shutter sample: the shot pass keeps each hair's
// shortest length over both, so the shirt holds over the whole shutter.
std::string records_path(const std::string& dir, int frame, int sample) {
  return frame_path(dir, frame, "_s" + std::to_string(sample) + ".ptrimr");
}

// Whether every file the simulation writes for frame `f` is good: a rerun steps
// through such a frame without writing it again.
bool simulated(const std::string& dir, const farm::Identity& id, int f) {
  bool ok = farm::sealed_ok(frame_path(dir, f, ".pguide"), id, Kind::GuideCache, uint32_t(f), kEvery) &&
            farm::sealed_ok(frame_path(dir, f, ".mesh"), id, Kind::Mesh, uint32_t(f), kEvery);
  for (int k = 0; k < kSamples; ++k) {
    ok = ok && farm::sealed_ok(records_path(dir, f, k), id, Kind::TrimRecords, uint32_t(f), uint32_t(k));
  }
  return ok;
}

void simulate(const std::string& obj, const std::string& dir, int frames, uint32_t hairs) {
  creature::Stopwatch clock;
  const farm::Identity id = shot_identity(obj, hairs, frames);
  const std::string groom_path = dir + "/creature.pgroom";
  const bool groom_done = farm::sealed_ok(groom_path, id, Kind::Groom, kEvery, kEvery);
  std::vector<bool> done(size_t(frames), false);
  int todo = 0;
  for (int f = 0; f < frames; ++f) done[size_t(f)] = simulated(dir, id, f), todo += !done[size_t(f)];
  if (groom_done && todo == 0) {
    std::printf("sim: the groom file and every file of the %d frames are already good\n", frames);
    return;
  }
  const creature::Mesh rest = creature::load_obj(obj);
  if (rest.normals.empty()) throw std::runtime_error(obj + ": the shot needs vertex normals");
  PelageStampParams sp = pelage_stamp_params_defaults();
  sp.target_count = kGuides, sp.seed = 1;
  const std::vector<PelageRoot> guide_roots = creature::stamp(rest, sp);
  const std::vector<float> rest_points = creature::combed_guides(rest, guide_roots, kCvs, kGuideLength);
  if (!groom_done) {
    const std::vector<unsigned char> groom =
        creature::groom_file(rest, guide_roots, rest_points, kCvs, hairs, kPatchSize);
    write_sealed(groom_path, id, Kind::Groom, kEvery, kEvery, groom.data(), groom.size());
  }
  const Asset asset(groom_path);
  const PelageGuideSet set = asset.set();
  std::printf("sim: groom file%s, %zu hairs on %zu guides: %.2f s\n", groom_done ? " (already good)" : "",
              asset.info.strand_count, guide_roots.size(), clock.seconds());

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

  // A killed simulation goes on from the state saved after the last frame
  // that it, and every frame before it, finished: the same bits as a run
  // that was never killed (pelage_sim_restore).
  int start = 0;
  for (int f = 0; f < frames && done[size_t(f)]; ++f) {
    if (farm::sealed_ok(frame_path(dir, f, ".psim"), id, Kind::SimState, uint32_t(f), kEvery)) start = f + 1;
  }
  // A state the library refuses (another state format, a damaged file the
  // seal did not catch) does not stop the shot: the one before it is
  // tried, down to stepping again from frame 0, which rewrites nothing good.
  while (start > 0) {
    const std::vector<unsigned char> state =
        farm::read_sealed(frame_path(dir, start - 1, ".psim"), id, Kind::SimState, uint32_t(start - 1), kEvery);
    if (pelage_sim_restore(sim.get(), state.data(), state.size()) == PELAGE_STATUS_OK) {
      std::printf("sim: frames 0 to %d already good: going on from the state saved after frame %d\n", start - 1,
                  start - 1);
      break;
    }
    std::fprintf(stderr, "sim: the state saved after frame %d is refused (%s); trying an earlier one\n", start - 1,
                 pelage_last_error());
    --start;
  }
  check(pelage_guide_cache_size(set.guide_count, kCvs, kSamples, 0, &bytes), "pelage_guide_cache_size");
  std::vector<unsigned char> cache(bytes);
  for (int f = start; f < frames; ++f) {
    clock = {};
    std::vector<creature::Mesh> meshes;
    std::vector<std::unique_ptr<creature::Frame>> samples;
    std::string written;
    // A frame already written after the restored state is stepped through
    // (the simulation carries state from frame to frame), not written again.
    const bool write = !done[size_t(f)];
    for (int k = 0; k < kSamples; ++k) {
      meshes.push_back(posed(rest, (float(f) + float(k) / kSamples) / kFps));
      samples.push_back(std::make_unique<creature::Frame>(meshes[k], rest_guides, ep));
      const PelageFrame frame = samples[k]->get();
      PelageStepParams step = pelage_step_params_defaults();
      step.dt = 1.0f / (kFps * kSamples);
      step.colliders = &colliders;
      check(pelage_sim_step(sim.get(), frame, &step, nullptr), "pelage_sim_step");
      check(pelage_frame_set_sim_guides(frame, sim.get(), PelageRun{0, nullptr, nullptr}), "pelage_frame_set_sim_guides");
      const std::string records = records_path(dir, f, k);
      if (write && !farm::sealed_ok(records, id, Kind::TrimRecords, uint32_t(f), uint32_t(k))) {
        const size_t met = write_trim_records(records, id, f, k, frame, meshes[k], colliders, set.guide_count);
        written += " trim records " + std::to_string(k) + " (" + std::to_string(met) +
                   " guides meet the shirt or the body),";
      }
    }
    const std::string cache_path = frame_path(dir, f, ".pguide"), mesh_path = frame_path(dir, f, ".mesh");
    if (write && !farm::sealed_ok(cache_path, id, Kind::GuideCache, uint32_t(f), kEvery)) {
      const PelageFrame at[kSamples] = {samples[0]->get(), samples[1]->get()};
      check(pelage_guide_cache_write(&set, at, kSamples, 0, PelageRun{1, nullptr, nullptr}, cache.data(), cache.size(),
                                     &bytes),
            "pelage_guide_cache_write");
      write_sealed(cache_path, id, Kind::GuideCache, uint32_t(f), kEvery, cache.data(), bytes);
      written += " guide cache " + std::to_string(bytes / 1000) + " KB,";
    }
    if (write && !farm::sealed_ok(mesh_path, id, Kind::Mesh, uint32_t(f), kEvery)) {
      const std::vector<unsigned char> mesh = mesh_file(meshes);
      write_sealed(mesh_path, id, Kind::Mesh, uint32_t(f), kEvery, mesh.data(), mesh.size());
      written += " mesh,";
    }
    // Last, so a saved state follows its frame's files.
    const std::string state_path = frame_path(dir, f, ".psim");
    if (!farm::sealed_ok(state_path, id, Kind::SimState, uint32_t(f), kEvery)) {
      check(pelage_sim_state_size(sim.get(), &bytes), "pelage_sim_state_size");
      std::vector<unsigned char> state(bytes);
      check(pelage_sim_save(sim.get(), state.data(), state.size(), &bytes), "pelage_sim_save");
      write_sealed(state_path, id, Kind::SimState, uint32_t(f), kEvery, state.data(), bytes);
      written += " simulation state,";
    }
    if (written.empty()) {
      std::printf("sim: frame %d: already good, stepped through: %.2f s\n", f, clock.seconds());
    } else {
      written.pop_back();
      std::printf("sim: frame %d: wrote%s: %.2f s\n", f, written.c_str(), clock.seconds());
    }
  }
}

// --- The shot pass ------------------------------------------------------------

void reduce(const std::string& dir, int frames) {
  const Asset asset(dir + "/creature.pgroom");
  if (uint32_t(frames) != asset.id.frames) {
    throw std::runtime_error(dir + "/creature.pgroom: the groom of a shot of " + std::to_string(asset.id.frames) +
                             " frames, not " + std::to_string(frames));
  }
  const std::string out = dir + "/shot.ptriml";
  if (farm::sealed_ok(out, asset.id, Kind::TrimLengths, kEvery, kEvery)) {
    std::printf("reduce: %s is already good\n", out.c_str());
    return;
  }
  std::vector<uint16_t> lengths(asset.info.strand_count, PELAGE_TRIM_WHOLE);
  for (int f = 0; f < frames; ++f) {
    for (int k = 0; k < kSamples; ++k) {
      const std::vector<unsigned char> file =
          farm::read_sealed(records_path(dir, f, k), asset.id, Kind::TrimRecords, uint32_t(f), uint32_t(k));
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
  write_sealed(out, asset.id, Kind::TrimLengths, kEvery, kEvery, file.data(), bytes);
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
  const std::string mesh_path = frame_path(dir, f, ".mesh");
  const std::vector<creature::Mesh> meshes =
      read_meshes(mesh_path, farm::read_sealed(mesh_path, asset.id, Kind::Mesh, uint32_t(f), kEvery));
  const std::vector<unsigned char> cache =
      farm::read_sealed(frame_path(dir, f, ".pguide"), asset.id, Kind::GuideCache, uint32_t(f), kEvery);
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
  const std::vector<unsigned char> png = farm::png_rgb(kImageSize, kImageSize, rgb, asset.id, uint32_t(f));
  farm::write_atomic(frame_path(dir, f, ".png"), png.data(), png.size());
  std::printf("render: frame %d: %zu hairs x %d samples expanded %.2f s, BVH %.2f s, rendered %.2f s\n", f, n,
              kSamples, expand_s, build_s, clock.seconds() - expand_s - build_s);
}

void render(const std::string& dir, int first, int count) {
  const Asset asset(dir + "/creature.pgroom");
  if (first < 0 || count < 1 || int64_t(first) + count > int64_t(asset.id.frames)) {
    throw std::runtime_error("frames " + std::to_string(first) + " to " + std::to_string(first + count - 1) +
                             " are not all in this shot's " + std::to_string(asset.id.frames) + " frames");
  }
  std::vector<int> todo;
  for (int f = first; f < first + count; ++f) {
    if (farm::png_ok(frame_path(dir, f, ".png"), asset.id, uint32_t(f))) {
      std::printf("render: frame %d: already good\n", f);
    } else {
      todo.push_back(f);
    }
  }
  if (todo.empty()) return;
  std::printf("render: %zu of frames %d to %d to render\n", todo.size(), first, first + count - 1);
  const std::string lengths_path = dir + "/shot.ptriml";
  const std::vector<unsigned char> file = farm::read_sealed(lengths_path, asset.id, Kind::TrimLengths, kEvery, kEvery);
  std::vector<uint16_t> lengths(asset.info.strand_count);
  size_t strands = 0;
  check(pelage_trim_lengths_read(file.data(), file.size(), lengths.data(), lengths.size(), &strands),
        "pelage_trim_lengths_read");
  if (strands != lengths.size()) throw std::runtime_error(lengths_path + ": the lengths of another groom");
  creature::Device device;
  for (int f : todo) render_frame(asset, lengths, device, dir, f);
}

// What is left of the shot: a line for each job, for farm/shot.sh to submit
// only those (the render line lists the frames without a good image).
void status(const std::string& obj, const std::string& dir, int frames, uint32_t hairs) {
  const farm::Identity id = shot_identity(obj, hairs, frames);
  bool sim = farm::sealed_ok(dir + "/creature.pgroom", id, Kind::Groom, kEvery, kEvery);
  for (int f = 0; f < frames && sim; ++f) sim = simulated(dir, id, f);
  std::printf("sim %s\n", sim ? "done" : "todo");
  std::printf("reduce %s\n",
              farm::sealed_ok(dir + "/shot.ptriml", id, Kind::TrimLengths, kEvery, kEvery) ? "done" : "todo");
  std::printf("render");
  for (int f = 0; f < frames; ++f) {
    if (!farm::png_ok(frame_path(dir, f, ".png"), id, uint32_t(f))) std::printf(" %d", f);
  }
  std::printf("\n");
}

}  // namespace

int main(int argc, char** argv) try {
  // A task killed mid-run still leaves its progress in the log.
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  farm::install_signal_cleanup();
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
  } else if (a.size() >= 4 && a[0] == "status") {
    status(a[1], a[2], number(3), hairs(4));
  } else {
    std::fprintf(stderr, "usage: shot sim|local|status <creature.obj> <dir> <frames> [hairs]\n"
                         "       shot reduce <dir> <frames>\n"
                         "       shot render <dir> <first frame> <count>\n");
    return 2;
  }
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "shot: %s\n", e.what());
  return 1;
}

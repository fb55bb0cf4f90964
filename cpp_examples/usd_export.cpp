// A frame of fur as a USD BasisCurves prim (catmullRom, pinned), with the
// per-curve primvars shaders need: the root's surface UV, the strand id and
// its LOD rank. Written as USDA text, which Houdini/Solaris, Maya and
// RenderMan read; tests/usd/check_usd.py reads it back with Pixar's own
// reader (usd-core) and compares it with the raw floats written beside it.
//
//   usd_export <creature.obj> <out.usda> [hairs]    (also writes <out.usda>.raw)
#include <pelage.h>

#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "creature_io.h"

int main(int argc, char** argv) try {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s creature.obj out.usda [hairs]\n", argv[0]);
    return 2;
  }
  const std::string path = argv[2];
  const uint32_t hairs = argc > 3 ? uint32_t(std::stoul(argv[3])) : 20000u;
  const creature::Mesh mesh = creature::load_obj(argv[1]);
  PelageStampParams sp = pelage_stamp_params_defaults();
  sp.target_count = 2000, sp.seed = 1;
  const std::vector<PelageRoot> guide_roots = creature::stamp(mesh, sp);
  sp.target_count = hairs, sp.seed = 2;
  const std::vector<PelageRoot> roots = creature::stamp(mesh, sp);
  const size_t n = roots.size();
  const uint32_t cvs = 8;
  const std::vector<float> guide_points = creature::combed_guides(mesh, guide_roots, cvs, 0.05f);
  const PelageGuidesDesc guides = creature::guides_desc(guide_roots, guide_points, cvs);
  const std::vector<PelageStrandBinding> bindings =
      creature::bind(mesh, guides, roots.data(), n, pelage_bind_params_defaults());
  PelageGroomMaps maps = pelage_groom_maps_defaults();
  maps.kink_amplitude.constant = 0.03f, maps.clump.constant = 0.25f;
  const std::vector<PelageStrandGroom> grooms = creature::groom(mesh, maps, roots.data(), n);
  // raw ends: USD's "pinned" wrap runs each curve from its root to its tip
  PelageExpandParams ep = pelage_expand_params_defaults();
  ep.points_per_strand = cvs, ep.end_points = PELAGE_END_POINTS_RAW;
  creature::Expander expander(ep);
  const creature::Frame frame(mesh, guides, ep);
  std::vector<float> points(4 * cvs * n);
  expander.expand(frame, roots.data(), bindings.data(), grooms.data(), n, points.data(), cvs * n);

  std::ofstream out(path);
  out << "#usda 1.0\n(\n    defaultPrim = \"fur\"\n    metersPerUnit = 1\n    upAxis = \"Y\"\n)\n\n"
      << "def BasisCurves \"fur\"\n{\n"
      << "    uniform token type = \"cubic\"\n    uniform token basis = \"catmullRom\"\n"
      << "    uniform token wrap = \"pinned\"\n";
  char buf[96];
  auto list = [&](const char* decl, size_t count, auto item, const char* meta) {
    out << "    " << decl << " = [";
    for (size_t i = 0; i < count; ++i) out << (i ? ", " : "") << item(i);
    out << "]" << meta << "\n";
  };
  list("int[] curveVertexCounts", n, [&](size_t) { return std::to_string(cvs); }, "");
  list("point3f[] points", cvs * n, [&](size_t i) {
    const float* p = &points[4 * i];
    std::snprintf(buf, sizeof buf, "(%.9g, %.9g, %.9g)", double(p[0]), double(p[1]), double(p[2]));
    return std::string(buf);
  }, "");
  list("float[] widths", cvs * n, [&](size_t i) {
    std::snprintf(buf, sizeof buf, "%.9g", double(2.0f * points[4 * i + 3]));
    return std::string(buf);
  }, " (\n        interpolation = \"vertex\"\n    )");
  list("float2[] primvars:rootUV", n, [&](size_t i) {
    float uv[2];
    mesh.uv_at(roots[i].face, roots[i].u, roots[i].v, uv);
    std::snprintf(buf, sizeof buf, "(%.9g, %.9g)", double(uv[0]), double(uv[1]));
    return std::string(buf);
  }, " (\n        interpolation = \"uniform\"\n    )");
  list("int[] primvars:strandId", n, [&](size_t i) { return std::to_string(roots[i].id); },
       " (\n        interpolation = \"uniform\"\n    )");
  list("int[] primvars:lodRank", n, [&](size_t i) { return std::to_string(roots[i].rank); },
       " (\n        interpolation = \"uniform\"\n    )");
  out << "}\n";
  if (!out) throw std::runtime_error("cannot write " + path);
  out.close();

  // what pelage expanded, for the check: n, points per curve, then float4
  // points, then id and rank per curve
  std::ofstream raw(path + ".raw", std::ios::binary);
  const uint32_t head[2] = {uint32_t(n), cvs};
  raw.write(reinterpret_cast<const char*>(head), sizeof head);
  raw.write(reinterpret_cast<const char*>(points.data()), std::streamsize(points.size() * sizeof(float)));
  for (const PelageRoot& r : roots) raw.write(reinterpret_cast<const char*>(&r.id), 2 * sizeof(uint32_t));
  if (!raw) throw std::runtime_error("cannot write " + path + ".raw");
  std::printf("usd_export: %zu curves x %u points -> %s\n", n, cvs, path.c_str());
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "usd_export: %s\n", e.what());
  return 1;
}

#include "view/vtk_series.hpp"

#include "common/text_file.hpp"

#include <cmath>
#include <filesystem>
#include <fmt/format.h>
#include <ostream>

namespace gapflow {

namespace {

constexpr int kCircleSides = 48;  // a cylinder obstruction is drawn as this polygon

std::string frame_file(const char* kind, int index) { return fmt::format("{}_{:06d}.vtp", kind, index); }

std::vector<std::vector<Vec2>> boundary_polygons(const CompiledScenario& sc, const ShakeOffsets& o) {
  auto moved = [](const ConvexPolygon& p, Vec2 d) {
    std::vector<Vec2> v;
    for (Vec2 q : p.vertices) v.push_back({q.x + d.x, q.y + d.y});
    return v;
  };
  std::vector<std::vector<Vec2>> out{moved(sc.left_bottleneck_wall, o.left_wall),
                                     moved(sc.right_bottleneck_wall, o.right_wall),
                                     moved(sc.left_retaining_wall, {}), moved(sc.right_retaining_wall, {}),
                                     moved(sc.top_wall, {})};
  const ObstructionGeometry ob = displaced(sc.obstruction, o.obstruction);
  if (ob.shape == ObstructionShape::cylinder) {
    std::vector<Vec2> v;
    for (int k = 0; k < kCircleSides; ++k) {
      const double a = 2 * M_PI * k / kCircleSides;
      v.push_back({ob.circle.centre.x + ob.circle.radius * std::cos(a), ob.circle.centre.y + ob.circle.radius * std::sin(a)});
    }
    out.push_back(v);
  } else if (ob.shape != ObstructionShape::none) {
    out.push_back(moved(ob.polygon, {}));
  }
  return out;
}

template <class Value>
void data_array(std::ostream& o, const char* type, const char* name, int components, const std::vector<ParticleView>& ps,
                Value value) {
  o << fmt::format("      <DataArray type=\"{}\" Name=\"{}\" NumberOfComponents=\"{}\" format=\"ascii\">\n", type,
                   name, components);
  for (const ParticleView& p : ps) o << "        " << value(p) << "\n";
  o << "      </DataArray>\n";
}

void write_particles(std::ostream& o, const FrameState& f) {
  const auto& ps = f.particles;
  const size_t n = ps.size();
  o << "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
    << "  <PolyData>\n"
    << fmt::format("    <Piece NumberOfPoints=\"{}\" NumberOfVerts=\"{}\" NumberOfLines=\"0\" NumberOfStrips=\"0\" "
                   "NumberOfPolys=\"0\">\n",
                   n, n);
  o << "    <Points>\n";
  data_array(o, "Float64", "position_m", 3, ps, [](const ParticleView& p) { return fmt::format("{:.9g} {:.9g} {:.9g}", p.x, p.y, p.z); });
  o << "    </Points>\n    <PointData Scalars=\"radius_m\" Vectors=\"velocity_m_s\">\n";
  data_array(o, "Float64", "radius_m", 1, ps, [](const ParticleView& p) { return fmt::format("{:.9g}", p.radius); });
  data_array(o, "Float64", "velocity_m_s", 3, ps,
             [](const ParticleView& p) { return fmt::format("{:.9g} {:.9g} {:.9g}", p.vx, p.vy, p.vz); });
  data_array(o, "Float64", "speed_m_s", 1, ps, [](const ParticleView& p) { return fmt::format("{:.9g}", p.speed()); });
  data_array(o, "Int32", "id", 1, ps, [](const ParticleView& p) { return fmt::format("{}", p.id); });
  // 0 flowing, 1 arch (front of a clog), 2 passed, 3 stuck behind a clog (view/frame.hpp)
  data_array(o, "Int32", "state", 1, ps, [](const ParticleView& p) { return fmt::format("{}", static_cast<int>(p.state)); });
  if (f.model == "3d")
    data_array(o, "Float64", "spin_rad_s", 3, ps,
               [](const ParticleView& p) { return fmt::format("{:.9g} {:.9g} {:.9g}", p.wx, p.wy, p.wz); });
  o << "    </PointData>\n    <Verts>\n"
    << "      <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n       ";
  for (size_t i = 0; i < n; ++i) o << " " << i;
  o << "\n      </DataArray>\n      <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n       ";
  for (size_t i = 1; i <= n; ++i) o << " " << i;
  o << "\n      </DataArray>\n    </Verts>\n    </Piece>\n  </PolyData>\n</VTKFile>\n";
}

void write_boundary(std::ostream& o, const std::vector<std::vector<Vec2>>& polys) {
  size_t points = 0;
  for (const auto& p : polys) points += p.size();
  o << "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
    << "  <PolyData>\n"
    << fmt::format("    <Piece NumberOfPoints=\"{}\" NumberOfVerts=\"0\" NumberOfLines=\"0\" NumberOfStrips=\"0\" "
                   "NumberOfPolys=\"{}\">\n",
                   points, polys.size())
    << "    <Points>\n      <DataArray type=\"Float64\" Name=\"position_m\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (const auto& p : polys)
    for (Vec2 v : p) o << fmt::format("        {:.9g} {:.9g} 0\n", v.x, v.y);
  o << "      </DataArray>\n    </Points>\n    <CellData Scalars=\"part\">\n"
    << "      <DataArray type=\"Int32\" Name=\"part\" format=\"ascii\">\n       ";
  // 0 bottleneck wall, 1 retaining or top wall, 2 obstruction
  for (size_t i = 0; i < polys.size(); ++i) o << " " << (i < 2 ? 0 : i < 5 ? 1 : 2);
  o << "\n      </DataArray>\n    </CellData>\n    <Polys>\n"
    << "      <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n       ";
  for (size_t i = 0; i < points; ++i) o << " " << i;
  o << "\n      </DataArray>\n      <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n       ";
  size_t end = 0;
  for (const auto& p : polys) o << " " << (end += p.size());
  o << "\n      </DataArray>\n    </Polys>\n    </Piece>\n  </PolyData>\n</VTKFile>\n";
}

}  // namespace

VtkSeries::VtkSeries(const CompiledScenario& sc, std::string dir) : sc_(sc), dir_(std::move(dir)) {
  std::filesystem::create_directories(dir_);
}

void VtkSeries::write(const FrameState& f) {
  const int index = frames();
  const std::filesystem::path dir(dir_);
  write_file_atomically((dir / frame_file("particles", index)).string(), [&](std::ostream& o) { write_particles(o, f); });
  write_file_atomically((dir / frame_file("boundary", index)).string(),
                        [&](std::ostream& o) { write_boundary(o, boundary_polygons(sc_, f.offsets)); });
  times_.push_back(f.t);
}

void VtkSeries::finish() const {
  write_file_atomically((std::filesystem::path(dir_) / "run.pvd").string(), [&](std::ostream& o) {
    o << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
      << "  <Collection>\n";
    for (size_t i = 0; i < times_.size(); ++i) {
      const int k = static_cast<int>(i);
      o << fmt::format("    <DataSet timestep=\"{:.6f}\" group=\"\" part=\"0\" file=\"{}\"/>\n", times_[i],
                       frame_file("particles", k));
      o << fmt::format("    <DataSet timestep=\"{:.6f}\" group=\"\" part=\"1\" file=\"{}\"/>\n", times_[i],
                       frame_file("boundary", k));
    }
    o << "  </Collection>\n</VTKFile>\n";
  });
}

}  // namespace gapflow

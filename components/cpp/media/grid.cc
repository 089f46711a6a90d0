// grid — a heterogeneous medium whose coefficients vary over a box, given
// by voxel grids: Mitsuba 3's "heterogeneous" (a σ_t grid and an albedo),
// pbrt-v4's "uniformgrid" (a density grid times σ_a and σ_s) and
// "rgbgrid" (σ_a and σ_s grids of their own), and OpenVDB grids.
//
// The medium fills the unit cube [0, 1]³ of its grids, which to_world
// places (Mitsuba 3's gridvolume convention; pbrt's p0, p1 become a
// to_world). Outside it the medium is empty. Inside, at a point x:
//   σ_a(x) = scale · density(x) · sigma_a(x)
//   σ_s(x) = scale · density(x) · sigma_s(x)
// and, when albedo is given, σ_s(x) = σ_t(x) · albedo(x) and
// σ_a(x) = σ_t(x) · (1 − albedo(x)), with σ_t = σ_a + σ_s as above.
// Where it absorbs it emits emission(x) (pbrt's Le, the source term being
// σ_a·Le).
//
// Each quantity Q among density, sigma_a, sigma_s, albedo, emission is
// one of:
//   Q              float or rgb     the same value everywhere in the box
//   Q              float array      a grid given inline: nx·ny·nz values
//                                   (grey) or 3·nx·ny·nz (rgb), x fastest,
//                                   then y, then z, channels innermost
//   Q_filename     file             a grid file, .vol (Mitsuba's binary
//                                   format) or .vdb (OpenVDB; its grid
//                                   named by Q_grid_name, default Q)
// except that density's file is `filename` and its OpenVDB grid
// `grid_name` (default "density"). At least one quantity must be a grid
// (a medium with none is homogeneous).
//
// Parameters: GridMedium::Parameters() below; g, g2 and blend give the
// phase function (phase.h).
//
// Values are trilinearly interpolated between voxel centres (volume_grid.h).
// Grid voxels must be finite; negative ones (a simulation's round-off)
// count as 0 and albedo voxels are clamped to [0, 1]. Every grid may have
// its own resolution; all share the unit cube.
//
// Majorants come from a coarse grid (up to 16³ cells) of the largest σ_t
// any point of each cell can have, walked cell by cell along each ray as
// pbrt-v4's GridMedium does.
#include <algorithm>
#include <optional>
#include <string>

#include "coefficients.h"
#include "majorant_grid.h"
#include "phase.h"
#include "volume_files.h"
#include "volume_grid.h"
#include "yarf/plugin.h"

namespace yarf {
namespace {

// One quantity of the medium: a value everywhere in the box, or a grid.
struct Field {
  Vec3 value;
  std::optional<VolumeGrid> grid;
  bool file = false;  // the grid came from a file

  Vec3 At(Vec3 local, GridEdge edge) const { return grid ? grid->Lookup(local, edge) : value; }
  Vec3 Max(Vec3 lo, Vec3 hi) const { return grid ? grid->Max(lo, hi) : value; }
};

// The inline grid of property `key`, of resolution nx × ny × nz.
VolumeGrid InlineGrid(const Properties& props, const std::string& key) {
  const std::string what = "property '" + key + "'";
  if (!props.Has("nx") || !props.Has("ny") || !props.Has("nz"))
    throw Error(what + " is a grid given inline: its resolution nx, ny, nz must be given");
  VolumeGrid grid;
  const uint64_t voxels = GridVoxelCount(props.Int("nx", 0), props.Int("ny", 0), props.Int("nz", 0), what);
  grid.nx = int(props.Int("nx", 0));
  grid.ny = int(props.Int("ny", 0));
  grid.nz = int(props.Int("nz", 0));
  const std::vector<float>& values = props.FloatArray(key);
  if (values.size() != voxels && values.size() != 3 * voxels)
    throw Error(what + " has " + std::to_string(values.size()) + " values; a grid of " + std::to_string(grid.nx) +
                " x " + std::to_string(grid.ny) + " x " + std::to_string(grid.nz) + " voxels needs " +
                std::to_string(voxels) + " (grey) or " + std::to_string(3 * voxels) + " (rgb)");
  grid.channels = values.size() == voxels ? 1 : 3;
  grid.values = values;
  return grid;
}

// Quantity `key` (see the header), whose file is `file_key` and whose
// OpenVDB grid `grid_name_key` names; values must lie in [0, hi].
Field ReadField(const Properties& props, const std::string& key, const std::string& file_key,
                const std::string& grid_name_key, Vec3 fallback, float hi) {
  Field field;
  if (props.Has(key) && props.Has(file_key))
    throw Error("properties '" + key + "' and '" + file_key + "' both give " + key + ": give one");
  if (props.Has(file_key)) {
    const std::string what = "property '" + file_key + "'";
    field.grid = ReadGridFile(props.ResolvedFile(file_key), props.String(grid_name_key, key), what);
    field.grid->Sanitize(0, hi, what);
    field.file = true;
  } else if (props.HasFloatArray(key)) {
    field.grid = InlineGrid(props, key);
    field.grid->Sanitize(0, hi, "property '" + key + "'");
  } else {
    field.value = NonNegativeColor(props, key.c_str(), fallback);
    if (!(MaxComponent(field.value) <= hi))
      throw Error("property '" + key + "' must lie in [0, " + std::to_string(int(hi)) + "]");
  }
  return field;
}

GridEdge Edge(const Properties& props) {
  const std::string edge = props.String("edge", "clamp");
  if (edge == "clamp") return GridEdge::kClamp;
  if (edge == "zero") return GridEdge::kZero;
  throw Error("property 'edge' must be \"clamp\" or \"zero\", got \"" + edge + "\"");
}

class GridMedium final : public UniformPhaseMedium {
 public:
  static ParameterSchema Parameters() {
    ParameterSchema schema;
    // Each quantity: a value or an inline grid; or a grid file, and the
    // name of its grid in an OpenVDB file. No declared defaults: a default
    // would stand beside a file given instead.
    const auto quantity = [&](const std::string& key, const std::string& file_key, const std::string& grid_name_key,
                              const std::string& doc, double most) {
      Parameter value = Parameter::RgbGrid(key).Min(0).Doc(
          doc + "; the same everywhere, or an inline grid of nx·ny·nz values (grey) or 3·nx·ny·nz (rgb), x fastest");
      if (most < kInfinity) value.max = most;
      schema.push_back(std::move(value));
      schema.push_back(Parameter::File(file_key).Doc(key + " as a grid file, .vol or .vdb"));
      schema.push_back(
          Parameter::String(AssetKeyOf(file_key)).Doc("the SHA-256 of an uploaded grid file, in place of " + file_key));
      schema.push_back(Parameter::String(grid_name_key).Doc("the OpenVDB grid of that file; default " + key));
    };
    quantity("density", "filename", "grid_name", "scales sigma_a and sigma_s; default 1", kInfinity);
    quantity("sigma_a", "sigma_a_filename", "sigma_a_grid_name", "absorption per unit length; default 0", kInfinity);
    quantity("sigma_s", "sigma_s_filename", "sigma_s_grid_name", "scattering per unit length; default 1", kInfinity);
    quantity("albedo", "albedo_filename", "albedo_grid_name",
             "when given, splits sigma_a + sigma_s into scattering and absorption", 1.0);
    quantity("emission", "emission_filename", "emission_grid_name", "radiance where it absorbs, not scaled; default 0",
             kInfinity);
    schema.push_back(ScaleParameter());
    for (const char* axis : {"nx", "ny", "nz"})
      schema.push_back(Parameter::Int(axis).Min(1).Doc("the resolution of the inline grids"));
    schema.push_back(Parameter::Matrix("to_world").Doc("places the unit cube of the grids; identity when left out"));
    schema.push_back(Parameter::Bool("use_grid_bbox").Default(false).Doc(
        "place density's grid file where the file says (a .vol box, an OpenVDB transform) before to_world"));
    schema.push_back(Parameter::String("edge").Default("clamp").Choices({"clamp", "zero"}).Doc(
        "past the outer voxel centres: clamp to the border voxels (Mitsuba 3), or fade to 0 (pbrt-v4)"));
    for (Parameter& parameter : PhaseFunction::Parameters()) schema.push_back(std::move(parameter));
    return schema;
  }

  explicit GridMedium(const Properties& props)
      : UniformPhaseMedium(props),
        density_(ReadField(props, "density", "filename", "grid_name", Vec3(1, 1, 1), kInfinity)),
        sigma_a_(ReadField(props, "sigma_a", "sigma_a_filename", "sigma_a_grid_name", Vec3(0, 0, 0), kInfinity)),
        sigma_s_(ReadField(props, "sigma_s", "sigma_s_filename", "sigma_s_grid_name", Vec3(1, 1, 1), kInfinity)),
        emission_(ReadField(props, "emission", "emission_filename", "emission_grid_name", Vec3(0, 0, 0), kInfinity)),
        scale_(Scale(props)),
        edge_(Edge(props)),
        majorants_(1, 1, 1) {
    if (props.Has("albedo") || props.Has("albedo_filename"))
      albedo_ = ReadField(props, "albedo", "albedo_filename", "albedo_grid_name", Vec3(0, 0, 0), 1);
    const Field* fields[] = {&density_, &sigma_a_, &sigma_s_, &emission_, albedo_ ? &*albedo_ : nullptr};
    int resolution[3] = {0, 0, 0};
    for (const Field* field : fields)
      if (field && field->grid) {
        resolution[0] = std::max(resolution[0], field->grid->nx);
        resolution[1] = std::max(resolution[1], field->grid->ny);
        resolution[2] = std::max(resolution[2], field->grid->nz);
      }
    if (resolution[0] == 0)
      throw Error("a grid medium needs a grid (filename, or density, sigma_a, sigma_s, albedo or emission given "
                  "as one); with the same coefficients everywhere, use homogeneous");

    Transform unit_to_world = props.Matrix("to_world", Transform::Identity());
    if (props.Bool("use_grid_bbox", false)) {
      if (!density_.file || !density_.grid->has_placement)
        throw Error("property 'use_grid_bbox' needs a density grid file (filename) that places its grid");
      unit_to_world = unit_to_world * density_.grid->unit_to_file;
    }
    to_local_ = InverseAffine(unit_to_world, "property 'to_world'");

    majorants_ = MajorantGrid(std::min(resolution[0], 16), std::min(resolution[1], 16), std::min(resolution[2], 16));
    BuildMajorants();
    const Vec3 most_emission = emission_.Max(Vec3(0, 0, 0), Vec3(1, 1, 1));
    const Vec3 most_absorption = sigma_a_.Max(Vec3(0, 0, 0), Vec3(1, 1, 1));
    emits_ = MaxComponent(most_emission) > 0 && (MaxComponent(most_absorption) > 0 || albedo_.has_value());
  }

  void Majorants(std::span<const float> origin, std::span<const float> direction, std::span<const float> tmax,
                 MajorantSegments& out) const override {
    out.Clear();
    for (size_t i = 0; i < tmax.size(); ++i) {
      // The local ray keeps the world ray's parameter t: its direction is
      // not renormalised.
      const Vec3 o = to_local_.Point(Vec3::Load(&origin[3 * i]));
      const Vec3 d = to_local_.Vector(Vec3::Load(&direction[3 * i]));
      float t0, t1;
      if (ClipToUnitCube(o, d, tmax[i], t0, t1)) majorants_.Walk(o, d, t0, t1, out.segments);
      out.offsets.push_back(uint32_t(out.segments.size()));
    }
  }

  void Coefficients(std::span<const float> position, std::span<float> sigma_a, std::span<float> sigma_s,
                    std::span<float> emission) const override {
    for (size_t k = 0; 3 * k < position.size(); ++k) {
      const Vec3 local = to_local_.Point(Vec3::Load(&position[3 * k]));
      Vec3 a, s, e;
      if (local.x >= 0 && local.y >= 0 && local.z >= 0 && local.x <= 1 && local.y <= 1 && local.z <= 1) {
        const Vec3 density = density_.At(local, edge_) * scale_;
        a = density * sigma_a_.At(local, edge_);
        s = density * sigma_s_.At(local, edge_);
        if (albedo_) {
          const Vec3 t = a + s, albedo = albedo_->At(local, edge_);
          s = t * albedo;
          a = t * (Vec3(1, 1, 1) - albedo);
        }
        e = emission_.At(local, edge_);
      }
      a.Store(&sigma_a[3 * k]);
      s.Store(&sigma_s[3 * k]);
      e.Store(&emission[3 * k]);
    }
  }

  bool Emits() const override { return emits_; }

 private:
  // Each coarse cell's majorant: the largest density times the largest
  // σ_a + σ_s over the voxels that reach into it, the cell widened by a
  // sliver so that round-off in a ray's walk never leaves it short.
  void BuildMajorants() {
    const int n[3] = {majorants_.Resolution(0), majorants_.Resolution(1), majorants_.Resolution(2)};
    for (int z = 0; z < n[2]; ++z)
      for (int y = 0; y < n[1]; ++y)
        for (int x = 0; x < n[0]; ++x) {
          const Vec3 margin(1e-3f / float(n[0]), 1e-3f / float(n[1]), 1e-3f / float(n[2]));
          const Vec3 lo = Vec3(float(x) / float(n[0]), float(y) / float(n[1]), float(z) / float(n[2])) - margin;
          const Vec3 hi =
              Vec3(float(x + 1) / float(n[0]), float(y + 1) / float(n[1]), float(z + 1) / float(n[2])) + margin;
          const Vec3 sigma_t = density_.Max(lo, hi) * scale_ * (sigma_a_.Max(lo, hi) + sigma_s_.Max(lo, hi));
          if (!(MaxComponent(sigma_t) < kInfinity))
            throw Error("the medium's extinction overflows single precision: lower its scale or its values");
          majorants_.At(x, y, z) = sigma_t;
        }
  }

  Field density_, sigma_a_, sigma_s_, emission_;
  std::optional<Field> albedo_;
  float scale_;
  GridEdge edge_;
  Transform to_local_;
  MajorantGrid majorants_;
  bool emits_ = false;
};

}  // namespace
}  // namespace yarf

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::GridMedium>(registrar, "grid", "1.0.0",
                                   "a heterogeneous medium given by voxel grids (.vol, OpenVDB or inline) over a box");
}

// Mitsuba's integrator, sensor, film, reconstruction filter and sampler.
#include <cmath>
#include <string>

#include "importers/numbers.h"
#include "importers/properties_util.h"
#include "importers/xml_importer.h"

namespace yarf::importers {
namespace {

constexpr double kPi = 3.14159265358979323846;
// Limits shared with yarf's film and render options.
constexpr int64_t kMaxFilmSide = 16384, kMaxPixels = int64_t(1) << 26, kMaxSpp = int64_t(1) << 20;
constexpr int64_t kMaxDepth = 1 << 16;

double Degrees(double radians) { return radians * 180 / kPi; }
double Radians(double degrees) { return degrees * kPi / 180; }

}  // namespace

void MitsubaImporter::Integrator(const XmlElement& e) {
  XmlPlugin p(e, *this);
  const std::string& type = p.type();
  if (has_integrator_) {
    Warn(e.where, "second-integrator", "a second <integrator> ignored");
    return;
  }
  if (type == "moment") {
    // Its first nested integrator renders; yarf keeps every pixel's
    // variance anyway.
    const auto nested = p.Objects("integrator");
    if (nested.empty()) Fail(e.where, "integrator 'moment' needs a nested integrator");
    if (nested.size() > 1)
      Warn(e.where, "moment-integrators", "integrator 'moment': only its first nested integrator is rendered");
    p.WarnUnused();
    Integrator(*nested.front());
    return;
  }
  has_integrator_ = true;
  integrator_type_ = type;
  integrator_where_ = e.where;
  int64_t max_depth = -1;
  v1::Properties props;
  std::string transport = "path";
  if (type == "direct") {
    max_depth = 2;
    Warn(e.where, "integrator:direct", "integrator 'direct' rendered by the path tracer with max_depth 2");
    p.Accept({"emitter_samples", "bsdf_samples", "shading_samples", "hide_emitters"});
  } else {
    if (type == "ptracer") {
      transport = "light";
      p.Accept({"samples_per_pass"});
    } else if (type != "path" && type != "volpath" && type != "volpathmis") {
      // volpath is path where there are no media (and volpath where there
      // are: Run).
      Warn(e.where, "integrator:" + type,
           "integrator '" + type + "' is not available: yarf's path tracer used (no media, no AOVs)");
    }
    max_depth = p.Integer("max_depth", -1);
    if (max_depth < -1 || max_depth > kMaxDepth)
      Fail(p.WhereIs("max_depth"), "max_depth must be -1 (unbounded) or 0 to " + std::to_string(kMaxDepth));
    if (p.Has("rr_depth")) {
      const int64_t rr = p.Integer("rr_depth", 5);
      if (rr < 1 || rr > kMaxDepth) Fail(p.WhereIs("rr_depth"), "rr_depth must be at least 1");
      SetInt(props, "rr_depth", rr);
    }
    if (p.Boolean("hide_emitters", false))
      Warn(p.WhereIs("hide_emitters"), "hide_emitters", "hide_emitters is not supported: emitters stay visible");
  }
  SetInt(props, "max_depth", max_depth);
  *assembly_.scene().mutable_transport() = Spec(transport, std::move(props));
  if (type == "path" || type == "direct" || type == "ptracer" || type == "volpath" || type == "volpathmis")
    p.WarnUnused();
}

void MitsubaImporter::Sensor(const XmlElement& e) {
  XmlPlugin p(e, *this);
  const std::string& type = p.type();
  if (type == "radiancemeter") {
    RadianceMeter(p);
    return;
  }
  if (type == "irradiancemeter")
    Fail(e.where, "sensor 'irradiancemeter' must be declared inside the <shape> it measures");
  v1::Camera camera;
  if (type == "thinlens") {
    camera.set_model(v1::Camera::THIN_LENS);
    const double radius = p.Float("aperture_radius", 0);
    if (!(radius >= 0 && radius < 1e30)) Fail(p.WhereIs("aperture_radius"), "aperture_radius must be >= 0");
    camera.set_lens_radius(radius);
  } else if (type == "orthographic") {
    camera.set_model(v1::Camera::ORTHOGRAPHIC);
  } else if (type != "perspective") {
    Warn(e.where, "sensor:" + type,
         "sensor '" + type + "' is not supported: a perspective camera with its placement used");
  }

  const auto films = p.Objects("film");
  int64_t width = 768, height = 576;
  if (films.empty()) {
    auto& film = *assembly_.scene().mutable_film();
    film.set_width(width), film.set_height(height);
    film.mutable_filter()->set_kind(v1::ReconstructionFilter::GAUSSIAN);
  } else {
    Film(*films.front());
    width = assembly_.scene().film().width(), height = assembly_.scene().film().height();
  }
  const Matrix4 to_world = p.Transform("to_world");
  if (type == "orthographic") {
    // Mitsuba's orthographic sensor sees x in [-1, 1] of its own space
    // across the film, y in proportion: its to_world's scale sets the view.
    const double size_x = Length(to_world.Vector({1, 0, 0})), size_y = Length(to_world.Vector({0, 1, 0}));
    if (!(size_x > 0 && size_x < 1e30)) Fail(e.where, "orthographic: to_world scales its view to nothing");
    if (std::abs(size_x - size_y) > 1e-6 * size_x)
      Warn(e.where, "orthographic-stretch",
           "orthographic: to_world scales x and y differently: the view keeps the film's aspect, its x extent used");
    camera.set_view_size(2 * size_x);
    camera.set_fov_axis(v1::Camera::X);
  } else {
    SetFieldOfView(p, camera, width, height, e.where);
  }

  const double near_clip = p.Float("near_clip", 0.01), far_clip = p.Float("far_clip", 10000);
  if (!(near_clip >= 0 && far_clip > near_clip)) Fail(e.where, "need 0 <= near_clip < far_clip");
  camera.set_near_clip(near_clip);
  camera.set_far_clip(far_clip);
  const double focus = p.Float("focus_distance", far_clip);
  if (type == "thinlens") {
    if (!(focus > 0)) Fail(p.WhereIs("focus_distance"), "focus_distance must be positive");
    camera.set_focus_distance(focus);
  }
  for (const char* offset : {"principal_point_offset_x", "principal_point_offset_y"})
    if (p.Float(offset, 0) != 0)
      Warn(p.WhereIs(offset), "principal-point", "principal point offsets are not supported: ignored");
  SensorSamplerAndMedium(p);
  assembly_.SetCamera(std::move(camera), to_world, {-1, 0, 0}, e.where);
  if (type == "perspective" || type == "thinlens" || type == "orthographic") p.WarnUnused();
}

void MitsubaImporter::SensorSamplerAndMedium(XmlPlugin& p) {
  const auto samplers = p.Objects("sampler");
  if (samplers.empty()) {
    sample_count_ = 4;  // Mitsuba's independent sampler's default
    *assembly_.scene().mutable_sampler() = Spec("independent");
  } else {
    Sampler(*samplers.front());
  }
  p.Accept({"shutter_open", "shutter_close"});
  const auto media = p.Objects("medium");
  if (media.size() > 1) Fail(media[1]->where, "a sensor sits in one medium");
  if (!media.empty()) assembly_.SetCameraMedium(Medium(*media.front()));
}

// Mitsuba's radiancemeter: the ray from to_world's origin along its +z,
// or from `origin` along `direction`; to_world wins when both are given.
void MitsubaImporter::RadianceMeter(XmlPlugin& p) {
  Vec3d origin{0, 0, 0}, direction{0, 0, 1};
  if (p.Has("to_world")) {
    p.Accept({"origin", "direction"});
    const Matrix4 to_world = p.Transform("to_world");
    origin = to_world.Point({0, 0, 0});
    direction = to_world.Vector({0, 0, 1});
  } else if (p.Has("origin") || p.Has("direction")) {
    if (!p.Has("origin") || !p.Has("direction"))
      Fail(p.where(), "sensor 'radiancemeter': give origin and direction together (or to_world)");
    origin = p.Point("origin", origin);
    direction = p.Point("direction", direction);
  }
  if (!(Length(direction) > 0 && Length(direction) < 1e30))
    Fail(p.WhereIs(p.Has("to_world") ? "to_world" : "direction"), "sensor 'radiancemeter': its direction is zero");
  v1::Camera camera;
  camera.set_model(v1::Camera::RADIANCE_METER);
  const Vec3d target = origin + direction;
  camera.mutable_origin()->set_x(origin.x), camera.mutable_origin()->set_y(origin.y),
      camera.mutable_origin()->set_z(origin.z);
  camera.mutable_target()->set_x(target.x), camera.mutable_target()->set_y(target.y),
      camera.mutable_target()->set_z(target.z);
  Meter(p, std::move(camera));
}

void MitsubaImporter::IrradianceMeter(const XmlElement& e, const std::string& shape) {
  XmlPlugin p(e, *this);
  if (p.Has("to_world"))
    Fail(p.WhereIs("to_world"), "sensor 'irradiancemeter' takes no to_world: it sits on its shape");
  v1::Camera camera;
  camera.set_model(v1::Camera::IRRADIANCE_METER);
  camera.set_meter_shape(shape);
  Meter(p, std::move(camera));
}

void MitsubaImporter::Meter(XmlPlugin& p, v1::Camera camera) {
  const std::string what = "sensor '" + p.type() + "'";
  const auto films = p.Objects("film");
  // Mitsuba's default film is 768x576, which a meter refuses.
  if (films.empty()) Fail(p.where(), what + " needs a 1x1 <film>");
  Film(*films.front());
  v1::Film& film = *assembly_.scene().mutable_film();
  if (film.width() != 1 || film.height() != 1)
    Fail(films.front()->where, what + " measures one value: its film must be 1x1, not " +
                                   std::to_string(film.width()) + "x" + std::to_string(film.height()));
  // Every sample of the one pixel must weigh the same.
  if (film.filter().kind() != v1::ReconstructionFilter::BOX || film.filter().radius() < 0.5)
    Warn(films.front()->where, "meter-filter",
         what + ": the box filter of radius 0.5 used, so that every sample weighs the same");
  film.mutable_filter()->set_kind(v1::ReconstructionFilter::BOX);
  film.mutable_filter()->set_radius(0.5);
  if (p.Has("srf")) Warn(p.WhereIs("srf"), "meter-srf", what + ": srf is not supported: RGB is measured");
  p.Accept({"srf"});
  SensorSamplerAndMedium(p);
  assembly_.SetMeter(std::move(camera));
  p.WarnUnused();
}

// Field of view: fov along fov_axis, or a 35 mm focal length (which
// spans the diagonal).
void MitsubaImporter::SetFieldOfView(XmlPlugin& p, v1::Camera& camera, int64_t width, int64_t height,
                                     const SourceLocation& where) {
  const bool has_fov = p.Has("fov");
  if (has_fov && p.Has("focal_length")) Fail(where, "give fov or focal_length, not both");
  std::string axis = p.String("fov_axis", "x");
  double fov = 0;
  if (has_fov) {
    fov = p.Float("fov", 0);
  } else {
    std::string focal = p.String("focal_length", "50mm");
    if (focal.size() > 2 && focal.substr(focal.size() - 2) == "mm") focal.resize(focal.size() - 2);
    const auto f = ParseDouble(focal);
    if (!f || !(*f > 0)) Fail(p.WhereIs("focal_length"), "focal_length must be a positive length like \"50mm\"");
    fov = Degrees(2 * std::atan(std::hypot(36.0, 24.0) / (2 * *f)));
    axis = "diagonal";
  }
  if (!(fov > 0 && fov < 180)) Fail(p.WhereIs("fov"), "fov must lie in (0, 180) degrees");
  if (axis == "x") {
    camera.set_fov_axis(v1::Camera::X);
  } else if (axis == "y") {
    camera.set_fov_axis(v1::Camera::Y);
  } else if (axis == "smaller") {
    camera.set_fov_axis(v1::Camera::SMALLER);
  } else if (axis == "larger") {
    camera.set_fov_axis(v1::Camera::LARGER);
  } else if (axis == "diagonal") {
    // The same frustum, its angle measured along x.
    const double w = double(width), h = double(height);
    fov = Degrees(2 * std::atan(std::tan(Radians(fov) / 2) * w / std::hypot(w, h)));
    camera.set_fov_axis(v1::Camera::X);
  } else {
    Fail(p.WhereIs("fov_axis"), "fov_axis must be x, y, smaller, larger or diagonal, not '" + axis + "'");
  }
  camera.set_fov(fov);
}

void MitsubaImporter::Film(const XmlElement& e) {
  XmlPlugin p(e, *this);
  if (p.type() != "hdrfilm")
    Warn(e.where, "film:" + p.type(), "film '" + p.type() + "' rendered as an RGB film");
  const int64_t width = p.Integer("width", 768), height = p.Integer("height", 576);
  if (width < 1 || height < 1 || width > kMaxFilmSide || height > kMaxFilmSide || width * height > kMaxPixels)
    Fail(e.where, "film resolution " + std::to_string(width) + "x" + std::to_string(height) +
                      " is out of range (1 to 16384 per side, at most 2^26 pixels)");
  v1::Film& film = *assembly_.scene().mutable_film();
  film.set_width(uint32_t(width));
  film.set_height(uint32_t(height));
  // The part of the film rendered, in pixels.
  if (p.Has("crop_offset_x") || p.Has("crop_offset_y") || p.Has("crop_width") || p.Has("crop_height")) {
    const int64_t x0 = p.Integer("crop_offset_x", 0), y0 = p.Integer("crop_offset_y", 0);
    const int64_t w = p.Integer("crop_width", width), h = p.Integer("crop_height", height);
    if (!(x0 >= 0 && y0 >= 0 && w >= 1 && h >= 1 && x0 <= width - w && y0 <= height - h))
      Fail(e.where, "the crop window (crop_offset_x/y, crop_width/height) must lie inside the film");
    crop_ = std::to_string(x0) + "," + std::to_string(x0 + w) + "," + std::to_string(y0) + "," + std::to_string(y0 + h);
  }
  p.Accept({"pixel_format", "component_format", "file_format", "banner", "sample_border", "compensate", "rfilter"});

  v1::ReconstructionFilter& filter = *film.mutable_filter();
  const auto filters = p.Objects("rfilter");
  if (filters.empty()) {
    filter.set_kind(v1::ReconstructionFilter::GAUSSIAN);  // Mitsuba's default
  } else {
    XmlPlugin f(*filters.front(), *this);
    const std::string& type = f.type();
    if (type == "box") {
      filter.set_kind(v1::ReconstructionFilter::BOX);
      filter.set_radius(f.Float("radius", 0.5));
    } else if (type == "tent") {
      filter.set_kind(v1::ReconstructionFilter::TENT);
      filter.set_radius(f.Float("radius", 1.0));
    } else if (type == "mitchell" || type == "catmullrom") {
      // Mitsuba's catmullrom is its mitchell with B = 0, C = 1/2.
      const bool catmull_rom = type == "catmullrom";
      filter.set_kind(v1::ReconstructionFilter::MITCHELL);
      filter.set_radius(2);
      filter.set_b(catmull_rom ? 0 : f.Float("B", 1.0 / 3));
      filter.set_c(catmull_rom ? 0.5 : f.Float("C", 1.0 / 3));
    } else if (type == "lanczos") {
      filter.set_kind(v1::ReconstructionFilter::LANCZOS);
      const int64_t lobes = f.Integer("lobes", 3);
      if (lobes < 1 || lobes > 16) Fail(f.WhereIs("lobes"), "lanczos: lobes must lie in 1 to 16");
      filter.set_lobes(double(lobes));
      filter.set_radius(double(lobes));
    } else {
      filter.set_kind(v1::ReconstructionFilter::GAUSSIAN);
      if (type == "gaussian") {
        const double stddev = f.Float("stddev", 0.5);
        if (!(stddev > 0 && stddev <= 4)) Fail(f.WhereIs("stddev"), "gaussian: stddev must lie in (0, 4] pixels");
        filter.set_stddev(stddev);
        filter.set_radius(4 * stddev);
      } else {
        Warn(f.where(), "rfilter:" + type, "reconstruction filter '" + type + "' replaced by a gaussian");
      }
    }
    if (!(filter.radius() >= 0 && filter.radius() <= 64)) Fail(f.where(), "filter radius out of range");
    if (filter.kind() != v1::ReconstructionFilter::GAUSSIAN || type == "gaussian") f.WarnUnused();
  }
  p.WarnUnused();
}

void MitsubaImporter::Sampler(const XmlElement& e) {
  XmlPlugin p(e, *this);
  const std::string& type = p.type();
  const int64_t count = p.Integer("sample_count", 4);
  if (count < 1 || count > kMaxSpp)
    Fail(p.WhereIs("sample_count"), "sample_count must lie in 1 to " + std::to_string(kMaxSpp));
  sample_count_ = uint32_t(count);
  v1::ComponentSpec& sampler = *assembly_.scene().mutable_sampler();
  if (type == "independent") {
    sampler = Spec("independent");
  } else if (type == "stratified" || type == "multijitter" || type == "orthogonal") {
    if (type == "orthogonal")
      Warn(e.where, "sampler:orthogonal", "sampler 'orthogonal' replaced by yarf's stratified sampler");
    v1::Properties props;
    SetInt(props, "sample_count", count);
    sampler = Spec("stratified", std::move(props));
    if (!p.Boolean("jitter", true)) Warn(p.WhereIs("jitter"), "jitter", "unjittered sampling is not supported");
  } else if (type == "ldsampler") {
    sampler = Spec("sobol");
  } else {
    Warn(e.where, "sampler:" + type, "sampler '" + type + "' replaced by the independent sampler");
    sampler = Spec("independent");
  }
  if (p.Has("seed")) {
    p.Integer("seed", 0);
    Warn(p.WhereIs("seed"), "sampler-seed", "the sampler's seed is a render option in yarf (--seed): ignored");
  }
  p.Accept({"scramble_seed"});
  p.WarnUnused();
}

}  // namespace yarf::importers

// pbrt's Camera, Film, Sampler, PixelFilter and Integrator.
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "importers/pbrt_importer.h"
#include "importers/properties_util.h"

namespace yarf::importers {
namespace {

constexpr int64_t kMaxFilmSide = 16384, kMaxPixels = int64_t(1) << 26, kMaxSpp = int64_t(1) << 20;
constexpr int64_t kMaxDepth = 1 << 16;

}  // namespace

void PbrtImporter::Camera(const std::string& type, PbrtParams& params, const SourceLocation& where) {
  if (has_camera_) Fail(where, "a second Camera");
  has_camera_ = true;
  const bool orthographic = type == "orthographic", spherical = type == "spherical";
  if (type != "perspective" && !orthographic && !spherical)
    Warn(where, "camera:" + type, "camera '" + type + "' is not supported: a perspective camera used");
  // The CTM maps world to camera space; the camera names that frame.
  const auto camera_to_world = state_.ctm.Inverse();
  if (!camera_to_world) Fail(where, "the camera transform is singular");
  v1::Camera camera;
  camera.set_fov_axis(v1::Camera::SMALLER);  // pbrt's fov and screen window span the shorter image axis
  if (spherical) {
    camera.set_model(v1::Camera::SPHERICAL);
    const std::string mapping = params.String("mapping", "equiarea");
    if (mapping != "equiarea" && mapping != "equirect")
      Fail(params.WhereIs("mapping", where), "spherical camera: mapping must be \"equiarea\" or \"equirect\"");
    camera.set_spherical_mapping(mapping == "equiarea" ? v1::Camera::EQUAL_AREA : v1::Camera::EQUIRECTANGULAR);
    // pbrt-v4 reads and ignores these for a spherical camera.
    for (const char* ignored : {"lensradius", "focaldistance", "frameaspectratio", "screenwindow"})
      if (params.Has(ignored)) params.Find(ignored);
  } else if (orthographic) {
    // pbrt-v4's screen window spans [-1, 1] of camera space across the
    // shorter image axis, unless given; the camera transform scales it.
    camera.set_model(v1::Camera::ORTHOGRAPHIC);
    double extent = 2;
    if (params.Has("screenwindow")) {
      const std::vector<double> window = params.Numbers("screenwindow", {"float"});
      if (window.size() != 4 || !(window[1] > window[0]) || !(window[3] > window[2]))
        Fail(params.WhereIs("screenwindow", where), "screenwindow needs 4 values: xmin < xmax, ymin < ymax");
      if (std::abs(window[0] + window[1]) > 1e-6 * (window[1] - window[0]) ||
          std::abs(window[2] + window[3]) > 1e-6 * (window[3] - window[2]))
        Warn(params.WhereIs("screenwindow", where), "camera:screenwindow",
             "camera: an off-centre screenwindow is not supported: centred on the view axis");
      extent = std::min(window[1] - window[0], window[3] - window[2]);
    }
    const double scale = Length(camera_to_world->Vector({1, 0, 0}));
    if (std::abs(scale - Length(camera_to_world->Vector({0, 1, 0}))) > 1e-6 * scale)
      Warn(where, "orthographic-stretch", "orthographic: the camera transform scales x and y differently: x used");
    if (!(extent * scale > 0 && extent * scale < 1e30)) Fail(where, "orthographic: the view has no extent");
    camera.set_view_size(extent * scale);
  } else {
    const double fov = params.Float("fov", 90);
    if (!(fov > 0 && fov < 180)) Fail(params.WhereIs("fov", where), "fov must lie in (0, 180) degrees");
    camera.set_fov(fov);
  }
  const double lens_radius = spherical ? 0 : params.Float("lensradius", 0);
  const double focal_distance = spherical ? 1 : params.Float("focaldistance", 1e6);
  if (!(lens_radius >= 0 && lens_radius < 1e30) || !(focal_distance > 0))
    Fail(where, "need lensradius >= 0 and focaldistance > 0");
  if (lens_radius > 0 && orthographic) {
    Warn(params.WhereIs("lensradius", where), "orthographic-lens",
         "orthographic: a lens (depth of field) is not supported: everything in focus");
  } else if (lens_radius > 0) {
    camera.set_model(v1::Camera::THIN_LENS);
    camera.set_lens_radius(lens_radius);
    camera.set_focus_distance(focal_distance);
  }
  for (const char* unsupported : {"screenwindow", "frameaspectratio"})
    if (!spherical && params.Has(unsupported) && !(orthographic && std::string(unsupported) == "screenwindow")) {
      params.Find(unsupported);
      Warn(params.WhereIs(unsupported, where), std::string("camera:") + unsupported,
           std::string("camera: ") + unsupported + " is not supported: ignored");
    }
  // The film's exposure takes the time the shutter is open (Finish).
  shutter_time_ = params.Float("shutterclose", 1) - params.Float("shutteropen", 0);
  if (!(shutter_time_ > 0 && shutter_time_ < 1e12))
    Fail(where, "shutteropen and shutterclose must leave the shutter open a while (pbrt: else a black image)");
  if (type == "perspective" || orthographic || spherical)
    params.WarnUnused(diagnostics_, "camera '" + type + "'");

  // pbrt-v4's camera sits in the outside medium of the MediumInterface in force.
  if (!state_.outside_medium.empty()) {
    assembly_.SetCameraMedium(state_.outside_medium);
    medium_uses_.emplace_back(state_.outside_medium, state_.medium_where);
  }
  coordinate_systems_["camera"] = *camera_to_world;
  assembly_.SetCamera(std::move(camera), *camera_to_world, {1, 0, 0}, where);
}

void PbrtImporter::Film(const std::string& type, PbrtParams& params, const SourceLocation& where) {
  if (has_film_) Fail(where, "a second Film");
  has_film_ = true;
  if (type != "rgb") Warn(where, "film:" + type, "film '" + type + "' rendered as an RGB film");
  const int64_t width = params.Integer("xresolution", 1280), height = params.Integer("yresolution", 720);
  if (width < 1 || height < 1 || width > kMaxFilmSide || height > kMaxFilmSide || width * height > kMaxPixels)
    Fail(where, "film resolution " + std::to_string(width) + "x" + std::to_string(height) +
                    " is out of range (1 to 16384 per side, at most 2^26 pixels)");
  v1::Film& film = *assembly_.scene().mutable_film();
  film.set_width(uint32_t(width));
  film.set_height(uint32_t(height));
  // The part of the film rendered: a crop window in fractions of the
  // film (winning, as in pbrt-v4), else pixel bounds, cut to the film.
  if (params.Has("cropwindow")) {
    const std::vector<double> c = params.Numbers("cropwindow", {"float"});
    if (c.size() != 4) Fail(params.WhereIs("cropwindow", where), "cropwindow needs 4 values: x0 x1 y0 y1");
    const auto fraction = [](double v) { return std::to_string(std::clamp(v, 0.0, 1.0)); };
    const double x0 = std::min(c[0], c[1]), x1 = std::max(c[0], c[1]);
    const double y0 = std::min(c[2], c[3]), y1 = std::max(c[2], c[3]);
    // pbrt-v4 rounds each edge up to a pixel.
    if (std::ceil(width * std::clamp(x0, 0.0, 1.0)) >= std::ceil(width * std::clamp(x1, 0.0, 1.0)) ||
        std::ceil(height * std::clamp(y0, 0.0, 1.0)) >= std::ceil(height * std::clamp(y1, 0.0, 1.0)))
      Fail(params.WhereIs("cropwindow", where), "cropwindow leaves no pixel");
    crop_ = fraction(x0) + "," + fraction(x1) + "," + fraction(y0) + "," + fraction(y1);
    if (params.Has("pixelbounds"))
      Warn(params.WhereIs("pixelbounds", where), "film-crop", "pixelbounds and cropwindow: the crop window used");
    params.Accept({"pixelbounds"});
  } else if (params.Has("pixelbounds")) {
    const std::vector<double> b = params.Numbers("pixelbounds", {"integer"});
    if (b.size() != 4) Fail(params.WhereIs("pixelbounds", where), "pixelbounds needs 4 values: x0 x1 y0 y1");
    const auto cut = [](double v, int64_t size) { return int64_t(std::clamp(v, 0.0, double(size))); };
    const int64_t x0 = cut(b[0], width), x1 = cut(b[1], width), y0 = cut(b[2], height), y1 = cut(b[3], height);
    if (x0 != b[0] || x1 != b[1] || y0 != b[2] || y1 != b[3])
      Warn(params.WhereIs("pixelbounds", where), "film-crop", "pixelbounds reach past the film: cut to it");
    if (!(x0 < x1 && y0 < y1)) Fail(params.WhereIs("pixelbounds", where), "pixelbounds leave no pixel");
    crop_ = std::to_string(x0) + "," + std::to_string(x1) + "," + std::to_string(y0) + "," + std::to_string(y1);
  }
  iso_ = params.Float("iso", 100);
  if (!(iso_ > 0 && iso_ < 1e12)) Fail(params.WhereIs("iso", where), "iso must be positive");
  const double max_component = params.Float("maxcomponentvalue", std::numeric_limits<double>::infinity());
  if (!(max_component > 0)) Fail(params.WhereIs("maxcomponentvalue", where), "maxcomponentvalue must be positive");
  if (std::isfinite(max_component)) film.set_max_component_value(max_component);
  if (params.Has("exposuretime") && params.Float("exposuretime", 1) != 1)
    Warn(params.WhereIs("exposuretime", where), "film-exposure",
         "film exposuretime is not pbrt-v4's: the camera's shutteropen and shutterclose set the exposure");
  if (params.String("sensor", "cie1931") != "cie1931")
    Warn(params.WhereIs("sensor", where), "film-sensor", "camera sensor response curves are not supported");
  if (params.Float("whitebalance", 0) != 0)
    Warn(params.WhereIs("whitebalance", where), "film-whitebalance", "film white balance is not supported: ignored");
  params.Accept({"filename", "diagonal", "savefp16", "writefp16"});
  params.WarnUnused(diagnostics_, "film '" + type + "'");
}

void PbrtImporter::Sampler(const std::string& type, PbrtParams& params, const SourceLocation& where) {
  if (has_sampler_) Fail(where, "a second Sampler");
  has_sampler_ = true;
  int64_t count = params.Integer("pixelsamples", 16);
  v1::ComponentSpec& sampler = *assembly_.scene().mutable_sampler();
  if (type == "stratified") {
    count = params.Integer("xsamples", 4) * params.Integer("ysamples", 4);
    params.Accept({"jitter", "pixelsamples"});
  }
  if (count < 1 || count > kMaxSpp) Fail(where, "pixelsamples must lie in 1 to " + std::to_string(kMaxSpp));
  sample_count_ = uint32_t(count);
  if (type == "independent") {
    sampler = Spec("independent");
  } else if (type == "stratified") {
    v1::Properties props;
    SetInt(props, "sample_count", count);
    sampler = Spec("stratified", std::move(props));
  } else if (type == "halton") {
    sampler = Spec("halton");
  } else if (type == "zsobol") {
    sampler = Spec("zsobol");
  } else {
    if (type != "sobol" && type != "paddedsobol")
      Warn(where, "sampler:" + type, "sampler '" + type + "' replaced by yarf's Sobol sampler");
    sampler = Spec("sobol");
  }
  params.Accept({"randomization", "seed"});
  params.WarnUnused(diagnostics_, "sampler '" + type + "'");
}

void PbrtImporter::Accelerator(const std::string& type, PbrtParams& params, const SourceLocation& where) {
  // pbrt's own two make the image Embree's BVH makes; any other name is a
  // yarf Aggregate class (Scene.aggregate), its parameters its properties,
  // checked at Submit as every class is.
  if (type == "bvh" || type == "kdtree") {
    params.Accept({"maxnodeprims", "splitmethod", "intersectcost", "traversalcost", "emptybonus", "maxprims",
                   "maxdepth"});
    params.WarnUnused(diagnostics_, "accelerator '" + type + "'");
    return;
  }
  v1::Properties props;
  for (const PbrtParam& p : params.TakeUnread()) {
    const size_t count = p.numbers.size() + p.strings.size() + p.bools.size();
    if (count != 1) Fail(p.where, "accelerator '" + type + "': parameter '" + p.name + "' needs one value");
    if (p.type == "float") SetFloat(props, p.name, p.numbers[0]);
    else if (p.type == "integer") SetInt(props, p.name, int64_t(p.numbers[0]));
    else if (p.type == "bool") SetBool(props, p.name, p.bools[0]);
    else if (p.type == "string") SetString(props, p.name, p.strings[0]);
    else Fail(p.where, "accelerator '" + type + "': parameter '" + p.name + "' is a " + p.type +
                           ", not a float, integer, bool or string");
  }
  *assembly_.scene().mutable_aggregate() = Spec(type, std::move(props));
}

void PbrtImporter::PixelFilter(const std::string& type, PbrtParams& params, const SourceLocation& where) {
  if (has_filter_) Fail(where, "a second PixelFilter");
  has_filter_ = true;
  v1::ReconstructionFilter& filter = *assembly_.scene().mutable_film()->mutable_filter();
  double radius = 0;
  if (type == "box") {
    filter.set_kind(v1::ReconstructionFilter::BOX);
    radius = 0.5;
  } else if (type == "triangle") {
    filter.set_kind(v1::ReconstructionFilter::TENT);
    radius = 2;
  } else if (type == "mitchell") {
    filter.set_kind(v1::ReconstructionFilter::MITCHELL);
    radius = 2;
    filter.set_b(params.Float("B", 1.0 / 3));
    filter.set_c(params.Float("C", 1.0 / 3));
  } else if (type == "sinc") {
    filter.set_kind(v1::ReconstructionFilter::LANCZOS);
    radius = 4;
    filter.set_lobes(params.Float("tau", 3));
    if (!(filter.lobes() > 0)) Fail(params.WhereIs("tau", where), "sinc filter: tau must be positive");
  } else {
    filter.set_kind(v1::ReconstructionFilter::GAUSSIAN);
    radius = 1.5;
    if (type == "gaussian") {
      filter.set_stddev(params.Float("sigma", 0.5));
      if (!(filter.stddev() > 0)) Fail(params.WhereIs("sigma", where), "gaussian filter: sigma must be positive");
    } else {
      Warn(where, "filter:" + type, "pixel filter '" + type + "' replaced by a gaussian");
    }
  }
  const double x = params.Float("xradius", radius), y = params.Float("yradius", radius);
  // Submit holds them to the film's largest radius.
  if (!(x > 0 && y > 0)) Fail(where, "pixel filter radii must be positive");
  filter.set_radius(x);
  if (y != x) filter.set_radius_y(y);
  params.WarnUnused(diagnostics_, "pixel filter '" + type + "'");
}

void PbrtImporter::Integrator(const std::string& type, PbrtParams& params, const SourceLocation& where) {
  if (has_integrator_) Fail(where, "a second Integrator");
  has_integrator_ = true;
  integrator_type_ = type;
  integrator_where_ = where;
  if (type == "ambientocclusion") {
    // Its own parameters only: no depth, no light sampler. Unset, the
    // transport's default maxdistance is pbrt's, infinity (a scene's
    // numbers must be finite).
    v1::Properties props;
    SetBool(props, "cossample", params.Bool("cossample", true));
    if (params.Has("maxdistance")) {
      const double distance = params.Float("maxdistance", 0);
      if (!(distance > 0) || !std::isfinite(distance))
        Fail(params.WhereIs("maxdistance", where), "maxdistance must be > 0 and finite");
      SetFloat(props, "maxdistance", distance);
    }
    params.WarnUnused(diagnostics_, "integrator 'ambientocclusion'");
    *assembly_.scene().mutable_transport() = Spec("ambient_occlusion", std::move(props));
    return;
  }
  // pbrt's integrators and the yarf transport that estimates the same
  // image; simplepath and randomwalk sample differently, to the same limit,
  // and volpath is path where there are no media (volpath where there are:
  // ChooseVolumetricTransport).
  static const std::map<std::string, std::string> kTransports = {
      {"path", "path"},  {"volpath", "path"},   {"simplepath", "path"}, {"randomwalk", "path"},
      {"bdpt", "bdpt"},  {"lightpath", "light"}, {"sppm", "sppm"}};
  const auto known = kTransports.find(type);
  if (known == kTransports.end())
    Warn(where, "integrator:" + type, "integrator '" + type + "' is not available: yarf's path tracer used");
  const std::string transport = known == kTransports.end() ? "path" : known->second;
  const int64_t max_depth = params.Integer("maxdepth", 5);
  if (max_depth < 0 || max_depth > kMaxDepth)
    Fail(params.WhereIs("maxdepth", where), "maxdepth must lie in 0 to " + std::to_string(kMaxDepth));
  if (params.Bool("regularize", false))
    Warn(params.WhereIs("regularize", where), "regularize", "path regularization is not supported: ignored");
  params.Accept({"samplelights", "samplebsdf"});
  // pbrt-v4 samples emitting triangles by their solid angle where it is
  // fair; its light samplers are yarf's, its default the BVH.
  assembly_.scene().set_triangle_sampling(v1::Scene::TRIANGLE_SAMPLING_SOLID_ANGLE);
  const std::string light_sampler = params.String("lightsampler", "bvh");
  if (light_sampler == "bvh") {
    assembly_.scene().set_light_sampler(v1::Scene::LIGHT_SAMPLER_BVH);
  } else if (light_sampler == "power") {
    assembly_.scene().set_light_sampler(v1::Scene::LIGHT_SAMPLER_POWER);
  } else if (light_sampler == "uniform") {
    assembly_.scene().set_light_sampler(v1::Scene::LIGHT_SAMPLER_UNIFORM);
  } else {
    Fail(params.WhereIs("lightsampler", where), "lightsampler must be \"bvh\", \"power\" or \"uniform\"");
  }
  // pbrt counts scattering events, yarf (as Mitsuba) path segments: pbrt's
  // maxdepth 0 shows emitters only, which is yarf's max_depth 1.
  v1::Properties props;
  SetInt(props, "max_depth", max_depth + 1);
  if (transport == "sppm") {
    // pbrt-v4: radius is the initial search radius in scene units (default
    // 1); photonsperiteration −1, one photon path per pixel, keeps yarf's
    // default (the film may not be known yet), which changes noise only.
    if (const int64_t photons = params.Integer("photonsperiteration", -1); photons > 0) {
      if (photons > 50'000'000) Fail(params.WhereIs("photonsperiteration", where), "photonsperiteration above 5e7");
      SetInt(props, "photons_per_pass", photons);
    }
    const double radius = params.Float("radius", 1);
    if (!(radius > 0) || !std::isfinite(radius)) Fail(params.WhereIs("radius", where), "radius must be > 0");
    SetFloat(props, "initial_radius", radius);
    SetInt(props, "seed", params.Integer("seed", 0));
  }
  if (known != kTransports.end()) params.WarnUnused(diagnostics_, "integrator '" + type + "'");
  *assembly_.scene().mutable_transport() = Spec(transport, std::move(props));
}

}  // namespace yarf::importers

// embree_baseline.cpp -- see embree_baseline.hpp.
#include "embree_baseline.hpp"

#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace {

const char* rtc_error_name(RTCError code) {
  switch (code) {
    case RTC_ERROR_NONE: return "RTC_ERROR_NONE";
    case RTC_ERROR_UNKNOWN: return "RTC_ERROR_UNKNOWN";
    case RTC_ERROR_INVALID_ARGUMENT: return "RTC_ERROR_INVALID_ARGUMENT";
    case RTC_ERROR_INVALID_OPERATION: return "RTC_ERROR_INVALID_OPERATION";
    case RTC_ERROR_OUT_OF_MEMORY: return "RTC_ERROR_OUT_OF_MEMORY";
    case RTC_ERROR_UNSUPPORTED_CPU: return "RTC_ERROR_UNSUPPORTED_CPU";
    case RTC_ERROR_CANCELLED: return "RTC_ERROR_CANCELLED";
  }
  return "RTC_ERROR_?";
}

}  // namespace

void EmbreeTerrain::error_callback(void* user, RTCError code, const char* str) {
  // Never throw through Embree's C frames: record the first error and let
  // the constructor turn it into an exception after the failing call.
  auto* self = static_cast<EmbreeTerrain*>(user);
  if (self->error_.empty()) {
    self->error_ = std::string(rtc_error_name(code)) + ": " + (str ? str : "(no message)");
  }
}

bool EmbreeTerrain::memory_callback(void* user, ssize_t bytes, bool /*post*/) {
  // Called once per allocation (bytes > 0) or release (bytes < 0); a failed
  // allocation is undone by a matching negative call, so a running sum is
  // the device's live byte count.
  auto* self = static_cast<EmbreeTerrain*>(user);
  const long long now = self->mon_bytes_.fetch_add(bytes, std::memory_order_relaxed) + bytes;
  long long peak = self->mon_peak_.load(std::memory_order_relaxed);
  while (now > peak && !self->mon_peak_.compare_exchange_weak(peak, now, std::memory_order_relaxed)) {
  }
  return true;  // never veto an allocation
}

void EmbreeTerrain::throw_if_error(const char* where) {
  if (!error_.empty()) {
    throw std::runtime_error(std::string("EmbreeTerrain: ") + where + ": " + error_);
  }
  // Errors can in principle be recorded without the callback firing (e.g.
  // a null handle); the device error code is the authoritative check.
  const RTCError code = rtcGetDeviceError(device_);
  if (code != RTC_ERROR_NONE) {
    throw std::runtime_error(std::string("EmbreeTerrain: ") + where + ": " + rtc_error_name(code));
  }
}

EmbreeTerrain::EmbreeTerrain(const uint16_t* codes, int width, int height, double z_scale)
    : width_(width), height_(height) {
  if (!codes || width < 2 || height < 2) {
    throw std::invalid_argument("EmbreeTerrain: need a non-null DEM of at least 2x2 posts");
  }
  if (!std::isfinite(z_scale)) throw std::invalid_argument("EmbreeTerrain: z_scale not finite");
  const size_t w = static_cast<size_t>(width);
  const size_t h = static_cast<size_t>(height);
  const size_t n_verts = w * h;
  const size_t n_tris = 2 * (w - 1) * (h - 1);
  if (n_verts > std::numeric_limits<unsigned int>::max() ||
      3 * n_tris > std::numeric_limits<unsigned int>::max()) {
    throw std::invalid_argument("EmbreeTerrain: DEM too large for 32-bit indices");
  }

  // One device per terrain so the memory monitor sees only this scene.
  // threads=1: the benchmark compares single-thread build and trace cost.
  device_ = rtcNewDevice("threads=1");
  if (!device_) {
    throw std::runtime_error(std::string("EmbreeTerrain: rtcNewDevice failed: ") +
                             rtc_error_name(rtcGetDeviceError(nullptr)));
  }
  rtcSetDeviceErrorFunction(device_, &EmbreeTerrain::error_callback, this);
  rtcSetDeviceMemoryMonitorFunction(device_, &EmbreeTerrain::memory_callback, this);

  try {
    const auto t0 = std::chrono::steady_clock::now();

    // Vertex buffer: float3 per post.  Embree reads vertices with 16-byte
    // loads, so a shared buffer needs one extra float of padding at the end.
    vertices_.resize(3 * n_verts + 1);
    float* v = vertices_.data();
    for (size_t j = 0; j < h; ++j) {
      for (size_t i = 0; i < w; ++i) {
        *v++ = static_cast<float>(i);
        *v++ = static_cast<float>(j);
        *v++ = static_cast<float>(static_cast<double>(codes[j * w + i]) * z_scale);
      }
    }
    *v = 0.0f;

    // Index buffer: cell (i,j) -> (p00,p10,p11) and (p00,p11,p01), i.e. split
    // along the (i,j)-(i+1,j+1) diagonal.  Counter-clockwise seen from +z.
    indices_.resize(3 * n_tris);
    unsigned int* ix = indices_.data();
    for (size_t j = 0; j + 1 < h; ++j) {
      for (size_t i = 0; i + 1 < w; ++i) {
        const auto p00 = static_cast<unsigned int>(j * w + i);
        const auto p10 = p00 + 1u;
        const auto p01 = static_cast<unsigned int>(p00 + w);
        const auto p11 = p01 + 1u;
        *ix++ = p00; *ix++ = p10; *ix++ = p11;
        *ix++ = p00; *ix++ = p11; *ix++ = p01;
      }
    }

    // Everything Embree allocates from here on belongs to the scene.
    const long long base_bytes = mon_bytes_.load();
    mon_peak_.store(base_bytes);

    scene_ = rtcNewScene(device_);
    throw_if_error("rtcNewScene");
    // Static scene built once and traced many times: HIGH quality (SAH with
    // spatial splits) is Embree's best trace-performance setting.
    rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);
    rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_NONE);

    RTCGeometry geom = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
    throw_if_error("rtcNewGeometry");
    rtcSetGeometryBuildQuality(geom, RTC_BUILD_QUALITY_HIGH);
    rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, vertices_.data(), 0,
                               3 * sizeof(float), n_verts);
    rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, indices_.data(), 0,
                               3 * sizeof(unsigned int), n_tris);
    rtcCommitGeometry(geom);
    rtcAttachGeometry(scene_, geom);
    rtcReleaseGeometry(geom);  // the scene holds the reference now
    throw_if_error("geometry setup");

    rtcCommitScene(scene_);
    throw_if_error("rtcCommitScene");

    const auto t1 = std::chrono::steady_clock::now();
    build_seconds_ = std::chrono::duration<double>(t1 - t0).count();

    const long long scene_bytes = mon_bytes_.load() - base_bytes;
    const long long peak_bytes = mon_peak_.load() - base_bytes;
    embree_scene_bytes_ = scene_bytes > 0 ? static_cast<size_t>(scene_bytes) : 0;
    embree_peak_bytes_ = peak_bytes > 0 ? static_cast<size_t>(peak_bytes) : 0;
  } catch (...) {
    if (scene_) rtcReleaseScene(scene_);
    rtcReleaseDevice(device_);
    throw;
  }
}

EmbreeTerrain::~EmbreeTerrain() {
  if (scene_) rtcReleaseScene(scene_);
  if (device_) rtcReleaseDevice(device_);
}

bool EmbreeTerrain::intersect(const double org[3], const double dir[3], double tmax,
                              double* t_hit) const {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);

  RTCRayHit rh;
  rh.ray.org_x = static_cast<float>(org[0]);
  rh.ray.org_y = static_cast<float>(org[1]);
  rh.ray.org_z = static_cast<float>(org[2]);
  rh.ray.tnear = 0.0f;
  rh.ray.dir_x = static_cast<float>(dir[0]);
  rh.ray.dir_y = static_cast<float>(dir[1]);
  rh.ray.dir_z = static_cast<float>(dir[2]);
  rh.ray.time = 0.0f;
  rh.ray.tfar = static_cast<float>(tmax);
  rh.ray.mask = 0xFFFFFFFFu;  // -1: all geometry
  rh.ray.id = 0;
  rh.ray.flags = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;

  rtcIntersect1(scene_, &ctx, &rh);

  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
  *t_hit = static_cast<double>(rh.ray.tfar);
  return true;
}

// embree_baseline.hpp -- Intel Embree 3 reference tracer for the benchmark.
//
// Builds a triangle mesh from a 16-bit height field (two triangles per grid
// cell) and traces single rays with rtcIntersect1 on a single-threaded
// device.  This is the "general-purpose BVH" baseline that the fixed-point
// cone tracer is compared against (time per ray, build time, memory).
#ifndef CT_EMBREE_BASELINE_HPP
#define CT_EMBREE_BASELINE_HPP

#include <cstddef>
#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include <embree3/rtcore.h>

class EmbreeTerrain {
 public:
  // codes: row-major width*height 16-bit height samples; post (i,j) is the
  // vertex (x=i, y=j, z=codes[j*width+i]*z_scale).  Two triangles per grid
  // cell (cell (i,j) between posts i..i+1, j..j+1), split along the
  // (i,j)-(i+1,j+1) diagonal.  Throws std::invalid_argument on bad
  // dimensions and std::runtime_error on any Embree device error.
  EmbreeTerrain(const uint16_t* codes, int width, int height, double z_scale);
  ~EmbreeTerrain();

  EmbreeTerrain(const EmbreeTerrain&) = delete;
  EmbreeTerrain& operator=(const EmbreeTerrain&) = delete;

  // First hit along org + t*dir for t in [0, tmax] (t in units of |dir|, dir
  // need not be normalised); returns true and sets *t_hit on a hit.  Inputs
  // are rounded to float (Embree is float32 internally).
  bool intersect(const double org[3], const double dir[3], double tmax, double* t_hit) const;

  // Bytes Embree holds for the scene after commit (BVH, primitive data,
  // scene/geometry objects) as reported by the device memory monitor, plus
  // our own vertex/index buffers (shared with Embree, not copied by it).
  size_t memory_bytes() const { return embree_scene_bytes_ + buffer_bytes(); }
  // Peak bytes Embree had allocated during the build (includes builder
  // temporaries that are released by the end of rtcCommitScene), plus our
  // buffers.  Informational.
  size_t peak_build_bytes() const { return embree_peak_bytes_ + buffer_bytes(); }
  // Wall-clock seconds for geometry creation + rtcCommitScene (BVH build).
  double build_seconds() const { return build_seconds_; }

  int width() const { return width_; }
  int height() const { return height_; }
  size_t triangle_count() const { return indices_.size() / 3; }

 private:
  static void error_callback(void* user, RTCError code, const char* str);
  static bool memory_callback(void* user, ssize_t bytes, bool post);
  void throw_if_error(const char* where);
  size_t buffer_bytes() const {
    return vertices_.capacity() * sizeof(float) + indices_.capacity() * sizeof(unsigned int);
  }

  int width_ = 0;
  int height_ = 0;
  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
  std::vector<float> vertices_;        // xyz per post, +1 float of padding
  std::vector<unsigned int> indices_;  // 3 per triangle
  double build_seconds_ = 0.0;
  size_t embree_scene_bytes_ = 0;
  size_t embree_peak_bytes_ = 0;

  // Memory monitor state (atomic in case Embree calls the monitor from a
  // worker thread; with threads=1 it is normally the calling thread).
  std::atomic<long long> mon_bytes_{0};
  std::atomic<long long> mon_peak_{0};
  // First device error seen since the last check (set by error_callback).
  std::string error_;
};

#endif  // CT_EMBREE_BASELINE_HPP

// OctoMap side of the peer benchmark (scripts/bench-peers.sh): OcTree update time on the
// frames `sndt points` exported, per cell size, single thread.
//
// Usage: octomap_bench POINTS.bin CELL [CELL ...]   (cells in metres, e.g. 0.05 0.10 0.20)
//
// POINTS.bin (little-endian): magic "SNDTPTS1", u32 frame count, then per frame 3 x f32
// sensor origin, u32 point count n, n x 3 x f32 world points (host/src/output/points.rs).
//
// Per cell size: a warm-up pass inserts every frame into a fresh octomap::OcTree that is
// then discarded; the timed pass inserts every frame into another fresh tree, timing each
// insertPointCloud(cloud, origin, maxrange 20 m, lazy_eval false, discretize true) with
// std::chrono::steady_clock. The octomap::Pointcloud of each frame is built once, before
// both passes, outside the clock. Prints one line per cell size:
//   octomap cell=0.10 median_ms=... min_ms=... max_ms=... nodes=... leaves=...
// (median of an even count: the mean of the two middle frames).

#include <octomap/OcTree.h>
#include <octomap/Pointcloud.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

constexpr double kMaxRange = 20.0;  // sndt's Config::DEFAULT.max_range

struct Frame {
  octomap::point3d origin;
  octomap::Pointcloud cloud;
};

class Reader {
 public:
  explicit Reader(const std::vector<unsigned char>& bytes) : bytes_(bytes) {}

  uint32_t u32() {
    need(4);
    uint32_t v = 0;
    for (int i = 3; i >= 0; --i) v = (v << 8) | bytes_[pos_ + i];
    pos_ += 4;
    return v;
  }

  float f32() {
    uint32_t bits = u32();
    float v;
    std::memcpy(&v, &bits, sizeof v);
    return v;
  }

  void expect_magic(const char* magic) {
    size_t n = std::strlen(magic);
    need(n);
    if (std::memcmp(bytes_.data() + pos_, magic, n) != 0)
      throw std::runtime_error("not an SNDTPTS1 file");
    pos_ += n;
  }

  bool at_end() const { return pos_ == bytes_.size(); }

 private:
  void need(size_t n) const {
    if (bytes_.size() - pos_ < n) throw std::runtime_error("file ends early");
  }

  const std::vector<unsigned char>& bytes_;
  size_t pos_ = 0;
};

std::vector<Frame> read_frames(const char* path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(std::string("cannot open ") + path);
  std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)),
                                   std::istreambuf_iterator<char>());
  Reader r(bytes);
  r.expect_magic("SNDTPTS1");
  uint32_t count = r.u32();
  std::vector<Frame> frames(count);
  for (Frame& f : frames) {
    float ox = r.f32(), oy = r.f32(), oz = r.f32();
    f.origin = octomap::point3d(ox, oy, oz);
    uint32_t n = r.u32();
    f.cloud.reserve(n);
    for (uint32_t i = 0; i < n; ++i) {
      float x = r.f32(), y = r.f32(), z = r.f32();
      f.cloud.push_back(x, y, z);
    }
  }
  if (!r.at_end()) throw std::runtime_error("trailing bytes after the last frame");
  return frames;
}

// Inserts every frame into `tree`; the time of each insertPointCloud in ms.
std::vector<double> insert_all(octomap::OcTree& tree, const std::vector<Frame>& frames) {
  std::vector<double> ms;
  for (const Frame& f : frames) {
    auto t0 = std::chrono::steady_clock::now();
    tree.insertPointCloud(f.cloud, f.origin, kMaxRange, /*lazy_eval=*/false,
                          /*discretize=*/true);
    auto t1 = std::chrono::steady_clock::now();
    ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
  }
  return ms;
}

void bench_cell(const std::vector<Frame>& frames, double cell) {
  {
    octomap::OcTree warm(cell);
    insert_all(warm, frames);
  }
  octomap::OcTree tree(cell);
  std::vector<double> ms = insert_all(tree, frames);
  std::sort(ms.begin(), ms.end());
  size_t n = ms.size();
  double median = (ms[(n - 1) / 2] + ms[n / 2]) / 2.0;
  std::printf("octomap cell=%.2f median_ms=%.3f min_ms=%.3f max_ms=%.3f nodes=%zu leaves=%zu\n",
              cell, median, ms.front(), ms.back(), tree.size(), tree.getNumLeafNodes());
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s POINTS.bin CELL [CELL ...]\n", argv[0]);
    return 2;
  }
  try {
    std::vector<Frame> frames = read_frames(argv[1]);
    if (frames.empty()) throw std::runtime_error("no frames");
    size_t points = 0;
    for (const Frame& f : frames) points += f.cloud.size();
    std::printf("octomap frames=%zu points=%zu max_range=%.0f\n", frames.size(),
                points, kMaxRange);
    for (int i = 2; i < argc; ++i) bench_cell(frames, std::atof(argv[i]));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "octomap_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}

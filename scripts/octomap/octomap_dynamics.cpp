// How OctoMap's occupancy evolves, frame by frame, at given query points: for comparing how
// fast mappers clear objects that moved (sndt's own map against liboctomap's OcTree).
//
// Usage: octomap_dynamics POINTS.bin QUERIES.bin CELL OUT.txt   (CELL in metres, e.g. 0.1)
//
// POINTS.bin (little-endian): magic "SNDTPTS1", u32 frame count, then per frame 3 x f32
// sensor origin, u32 point count n, n x 3 x f32 world points (host/src/output/points.rs).
// QUERIES.bin (little-endian): magic "SNDTQRY1", u32 count m, then m x 3 x f32 query points
// in world metres (the host passes voxel centres).
//
// Every frame, in order, goes into one persistent octomap::OcTree(CELL) with OctoMap's
// default sensor model (set explicitly below) by insertPointCloud(cloud, origin, maxrange
// 20 m, lazy_eval false, discretize true); after each frame every query point is looked up
// with search(point) at the tree's full depth. OUT.txt gets the line
//   octomap_dynamics cell=<CELL> frames=<F> queries=<m>
// then one line per frame of exactly m characters, in query order: '1' the node exists and
// isNodeOccupied, '0' it exists and is free, '?' unknown (no node). OUT.txt is written under
// a temporary name and renamed at the end, so a failed run leaves no complete-looking file.
// Any error (usage, CELL, a file that cannot be read, bad magic, a truncated file, a
// non-finite coordinate) is printed to stderr and exits 1.

#include <octomap/OcTree.h>
#include <octomap/Pointcloud.h>

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

#include <unistd.h>

namespace {

constexpr double kMaxRange = 20.0;  // sndt's Config::DEFAULT.max_range

struct Frame {
    octomap::point3d origin;
    octomap::Pointcloud cloud;
};

// Little-endian fields of a file read whole; every error names the file.
class Reader {
public:
    Reader(const std::string& path, const std::vector<unsigned char>& bytes)
        : path_(path), bytes_(bytes) {}

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

    // Three f32, which must be finite (octomap's key computation is undefined for NaN).
    octomap::point3d point(const char* what) {
        float x = f32(), y = f32(), z = f32();
        if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z))
            fail(std::string("non-finite ") + what);
        return octomap::point3d(x, y, z);
    }

    void expect_magic(const char* magic) {
        size_t n = std::strlen(magic);
        need(n);
        if (std::memcmp(bytes_.data() + pos_, magic, n) != 0)
            fail(std::string("not a ") + magic + " file (bad magic)");
        pos_ += n;
    }

    // Throws unless at least `count` records of `size` bytes are left (before reserving
    // memory for a count read from the file).
    void need_records(uint64_t count, uint64_t size) const {
        if (count > (bytes_.size() - pos_) / size) fail("file ends early");
    }

    void expect_end() const {
        if (pos_ != bytes_.size()) fail("trailing bytes after the data");
    }

    [[noreturn]] void fail(const std::string& why) const {
        throw std::runtime_error(path_ + ": " + why + " (at byte " + std::to_string(pos_) + ")");
    }

private:
    void need(size_t n) const {
        if (bytes_.size() - pos_ < n) fail("file ends early");
    }

    const std::string& path_;
    const std::vector<unsigned char>& bytes_;
    size_t pos_ = 0;
};

std::vector<unsigned char> read_file(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error("cannot open " + path);
    std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)),
                                     std::istreambuf_iterator<char>());
    if (in.bad()) throw std::runtime_error("cannot read " + path);
    return bytes;
}

std::vector<Frame> read_frames(const std::string& path) {
    const std::vector<unsigned char> bytes = read_file(path);
    Reader r(path, bytes);
    r.expect_magic("SNDTPTS1");
    uint32_t count = r.u32();
    r.need_records(count, 16);  // each frame: origin and point count at least
    std::vector<Frame> frames(count);
    for (Frame& f : frames) {
        f.origin = r.point("sensor origin");
        uint32_t n = r.u32();
        r.need_records(n, 12);
        f.cloud.reserve(n);
        for (uint32_t i = 0; i < n; ++i) f.cloud.push_back(r.point("point"));
    }
    r.expect_end();
    return frames;
}

std::vector<octomap::point3d> read_queries(const std::string& path) {
    const std::vector<unsigned char> bytes = read_file(path);
    Reader r(path, bytes);
    r.expect_magic("SNDTQRY1");
    uint32_t count = r.u32();
    r.need_records(count, 12);
    std::vector<octomap::point3d> queries;
    queries.reserve(count);
    for (uint32_t i = 0; i < count; ++i) queries.push_back(r.point("query point"));
    r.expect_end();
    return queries;
}

// CELL: a finite number > 0 and nothing else.
double parse_cell(const char* text) {
    errno = 0;
    char* end = nullptr;
    double cell = std::strtod(text, &end);
    if (end == text || *end != '\0' || errno == ERANGE || !std::isfinite(cell) || cell <= 0.0)
        throw std::runtime_error(std::string("CELL must be a number of metres > 0, not \"") +
                                 text + "\"");
    return cell;
}

// One character per query point (see the top of the file).
char state(const octomap::OcTree& tree, const octomap::point3d& p) {
    // At the full depth; a pruned inner node that covers p is what search returns for it.
    const octomap::OcTreeNode* node = tree.search(p, tree.getTreeDepth());
    if (!node) return '?';
    return tree.isNodeOccupied(node) ? '1' : '0';
}

void run(const std::string& points_path, const std::string& queries_path, const char* cell_text,
         const std::string& out_path) {
    const double cell = parse_cell(cell_text);
    const std::vector<Frame> frames = read_frames(points_path);
    const std::vector<octomap::point3d> queries = read_queries(queries_path);

    octomap::OcTree tree(cell);
    // OctoMap's defaults (AbstractOccupancyOcTree's constructor), stated explicitly.
    tree.setProbHit(0.7);              // log-odds +0.85
    tree.setProbMiss(0.4);             // log-odds -0.41
    tree.setClampingThresMin(0.1192);  // log-odds -2.0
    tree.setClampingThresMax(0.971);   // log-odds +3.51
    tree.setOccupancyThres(0.5);       // log-odds 0

    const std::string tmp_path = out_path + ".tmp." + std::to_string(getpid());
    std::FILE* out = std::fopen(tmp_path.c_str(), "w");
    if (!out) throw std::runtime_error("cannot write " + tmp_path);
    try {
        std::fprintf(out, "octomap_dynamics cell=%g frames=%zu queries=%zu\n", cell,
                     frames.size(), queries.size());
        std::string line(queries.size(), '?');
        for (const Frame& f : frames) {
            tree.insertPointCloud(f.cloud, f.origin, kMaxRange, /*lazy_eval=*/false,
                                  /*discretize=*/true);
            for (size_t i = 0; i < queries.size(); ++i) line[i] = state(tree, queries[i]);
            std::fputs(line.c_str(), out);
            std::fputc('\n', out);
        }
        if (std::ferror(out)) throw std::runtime_error("cannot write " + tmp_path);
    } catch (...) {
        std::fclose(out);
        std::remove(tmp_path.c_str());
        throw;
    }
    if (std::fclose(out) != 0) {
        std::remove(tmp_path.c_str());
        throw std::runtime_error("cannot write " + tmp_path);
    }
    if (std::rename(tmp_path.c_str(), out_path.c_str()) != 0) {
        std::remove(tmp_path.c_str());
        throw std::runtime_error("cannot rename " + tmp_path + " to " + out_path + ": " +
                                 std::strerror(errno));
    }
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 5) {
        std::fprintf(stderr, "usage: %s POINTS.bin QUERIES.bin CELL OUT.txt\n", argv[0]);
        return 1;
    }
    try {
        run(argv[1], argv[2], argv[3], argv[4]);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "octomap_dynamics: %s\n", e.what());
        return 1;
    } catch (...) {
        std::fprintf(stderr, "octomap_dynamics: unknown error\n");
        return 1;
    }
    return 0;
}

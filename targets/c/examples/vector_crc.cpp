// The test vector through the C API from C++17: integrates
// targets/cortex-m4f/vector/frames.bin and prints the snapshot CRC, which must equal the
// Rust firmware's (expected_crc.txt). The map storage is a std::vector sized by
// sndt_map_bytes() with an alignas buffer, as a C++ node on a robot computer would hold it.
//
//   vector_crc_cpp FRAMES.BIN
#include <array>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "sndt.h"

namespace {

template <typename T>
T le(const std::vector<std::uint8_t>& b, std::size_t off) {
    std::uint32_t u = 0;
    for (std::size_t i = 0; i < sizeof(T); ++i) u |= std::uint32_t{b.at(off + i)} << (8 * i);
    T v;
    std::memcpy(&v, &u, sizeof v);
    return v;
}

void check(sndt_status s, const char* what) {
    if (s != SNDT_OK) throw std::runtime_error(std::string(what) + ": " + sndt_status_str(s));
}

// Storage for one map, aligned as the library requires.
struct alignas(SNDT_MAP_ALIGN) MapStorage {
    std::array<std::uint8_t, SNDT_MAP_BYTES> bytes;
};

}  // namespace

int main(int argc, char** argv) try {
    if (argc != 2) {
        std::fprintf(stderr, "usage: vector_crc_cpp FRAMES.BIN\n");
        return 2;
    }
    std::ifstream in(argv[1], std::ios::binary);
    const std::vector<std::uint8_t> v{std::istreambuf_iterator<char>(in), {}};
    if (v.size() < 56 || std::memcmp(v.data(), "SNDTVEC", 8) != 0)
        throw std::runtime_error("not a test vector");
    if (sndt_map_bytes() != SNDT_MAP_BYTES) throw std::runtime_error("capacity mismatch");

    const auto frames = le<std::uint16_t>(v, 10), probes = le<std::uint16_t>(v, 12);
    sndt_pinhole cam{le<float>(v, 32), le<float>(v, 36), le<float>(v, 40), le<float>(v, 44),
                     le<std::uint32_t>(v, 24), le<std::uint32_t>(v, 28)};
    sndt_config cfg = sndt_config_default();
    cfg.cell_size = le<float>(v, 48);

    auto storage = std::make_unique<MapStorage>();  // 476 KiB: on the heap, not the stack
    auto* map = reinterpret_cast<sndt_map*>(storage->bytes.data());
    check(sndt_map_init(map, sizeof(MapStorage), &cfg), "sndt_map_init");

    const std::size_t n = std::size_t{cam.width} * cam.height;
    std::vector<float> depth(n);
    std::size_t off = 56 + 8 * std::size_t{probes};
    for (unsigned k = 0; k < frames; ++k, off += 48 + 5 * n) {
        // Rotation (row-major) and translation as the vector stores them (the C program
        // goes through the 4x4 matrix instead: both must give the same map).
        std::array<float, 9> rot{};
        std::array<float, 3> t{};
        for (std::size_t i = 0; i < 9; ++i) rot[i] = le<float>(v, off + 4 * i);
        for (std::size_t i = 0; i < 3; ++i) t[i] = le<float>(v, off + 36 + 4 * i);
        for (std::size_t i = 0; i < n; ++i) depth[i] = le<float>(v, off + 48 + 4 * i);
        sndt_pose pose;
        check(sndt_pose_from_rt(rot.data(), t.data(), &pose), "sndt_pose_from_rt");
        sndt_depth_frame f{};
        f.camera = cam;
        f.depth_m = depth.data();
        f.labels = v.data() + off + 48 + 4 * n;
        f.stride = 1;
        f.len = n;
        sndt_frame_report r;
        check(sndt_integrate_depth(map, &pose, &f, &r), "sndt_integrate_depth");
        std::printf("frame %u: points %u\n", k, static_cast<unsigned>(r.points_used));
    }
    std::uint32_t crc = 0;
    check(sndt_checksum(map, &crc), "sndt_checksum");
    std::printf("snapshot crc 0x%08x\n", static_cast<unsigned>(crc));
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
}

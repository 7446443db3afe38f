/*
 * Integrates the firmware test vector (targets/cortex-m4f/vector/frames.bin) through the C
 * API and prints its snapshot CRC and the CRC of a 64x48 view rendered from the map; both
 * must equal the Rust firmware's (expected_crc.txt, expected_render_crc.txt). C99.
 *
 *   vector_crc FRAMES.BIN
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sndt.h"

/* Little-endian readers (the vector's byte order), independent of the host's. */
static uint32_t u32_at(const uint8_t *b) {
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}
static uint16_t u16_at(const uint8_t *b) { return (uint16_t)(b[0] | b[1] << 8); }
static float f32_at(const uint8_t *b) {
    uint32_t u = u32_at(b);
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

/* CRC-32 (IEEE 802.3, reflected), bit by bit. */
static uint32_t crc32_update(uint32_t crc, const uint8_t *p, size_t n) {
    size_t i;
    int k;
    for (i = 0; i < n; i++) {
        crc ^= p[i];
        for (k = 0; k < 8; k++) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
    }
    return crc;
}

static uint8_t *read_file(const char *path, size_t *len) {
    FILE *f = fopen(path, "rb");
    uint8_t *buf;
    long n;
    if (!f) return NULL;
    if (fseek(f, 0, SEEK_END) != 0 || (n = ftell(f)) < 0 || fseek(f, 0, SEEK_SET) != 0) {
        fclose(f);
        return NULL;
    }
    buf = malloc((size_t)n);
    if (buf && fread(buf, 1, (size_t)n, f) != (size_t)n) {
        free(buf);
        buf = NULL;
    }
    fclose(f);
    *len = (size_t)n;
    return buf;
}

#define CHECK(call)                                                                      \
    do {                                                                                 \
        sndt_status s_ = (call);                                                         \
        if (s_ != SNDT_OK) {                                                             \
            fprintf(stderr, "%s: %s\n", #call, sndt_status_str(s_));                     \
            return 1;                                                                    \
        }                                                                                \
    } while (0)

/* The map lives in static storage, as on a microcontroller. */
static uint8_t map_storage[SNDT_MAP_BYTES] __attribute__((aligned(SNDT_MAP_ALIGN)));

int main(int argc, char **argv) {
    size_t len = 0, n, off, k;
    uint8_t *v;
    float *depth;
    sndt_map *map = (sndt_map *)map_storage;
    sndt_config cfg = sndt_config_default();
    sndt_pinhole cam;
    sndt_pose pose;
    uint32_t crc, frames, probes, row;
    uint8_t labels[64 * 8];
    float distance[64 * 8];
    sndt_pinhole view;
    sndt_stats st;

    if (argc != 2 || !(v = read_file(argv[1], &len)) || len < 56 || memcmp(v, "SNDTVEC", 8) != 0) {
        fprintf(stderr, "usage: vector_crc FRAMES.BIN (a test vector)\n");
        return 2;
    }
    if (sndt_map_bytes() != SNDT_MAP_BYTES || u16_at(v + 14) != SNDT_CLASSES ||
        u32_at(v + 16) != SNDT_VOXELS || u32_at(v + 20) != SNDT_BLOCKS) {
        fprintf(stderr, "the library or the vector has other capacities than this program\n");
        return 2;
    }
    frames = u16_at(v + 10);
    probes = u16_at(v + 12);
    cam.width = u32_at(v + 24);
    cam.height = u32_at(v + 28);
    cam.fx = f32_at(v + 32);
    cam.fy = f32_at(v + 36);
    cam.cx = f32_at(v + 40);
    cam.cy = f32_at(v + 44);
    cfg.cell_size = f32_at(v + 48);
    n = (size_t)cam.width * cam.height;
    if (len != 56 + 8 * (size_t)probes + frames * (48 + 5 * n)) {
        fprintf(stderr, "%s: truncated\n", argv[1]);
        return 2;
    }
    CHECK(sndt_map_init(map, sizeof map_storage, &cfg));
    depth = malloc(n * sizeof *depth);
    if (!depth) return 2;
    off = 56 + 8 * (size_t)probes;
    for (k = 0; k < frames; k++, off += 48 + 5 * n) {
        float m[16] = {0};
        size_t i;
        sndt_depth_frame f;
        sndt_frame_report r;
        for (i = 0; i < 3; i++) {
            m[4 * i + 0] = f32_at(v + off + 12 * i);
            m[4 * i + 1] = f32_at(v + off + 12 * i + 4);
            m[4 * i + 2] = f32_at(v + off + 12 * i + 8);
            m[4 * i + 3] = f32_at(v + off + 36 + 4 * i);
        }
        m[15] = 1.0f;
        for (i = 0; i < n; i++) depth[i] = f32_at(v + off + 48 + 4 * i);
        CHECK(sndt_pose_from_matrix4(m, &pose));
        memset(&f, 0, sizeof f);
        f.camera = cam;
        f.depth_m = depth;
        f.labels = v + off + 48 + 4 * n;
        f.stride = 1;
        f.len = n;
        CHECK(sndt_integrate_depth(map, &pose, &f, &r));
        printf("frame %u: points %u, voxels +%u -%u\n", (unsigned)k, (unsigned)r.points_used,
               (unsigned)r.voxels_created, (unsigned)r.voxels_evicted);
    }
    CHECK(sndt_map_stats(map, &st));
    printf("voxels %u, blocks %u\n", (unsigned)st.voxels, (unsigned)st.blocks);
    CHECK(sndt_checksum(map, &crc));
    printf("snapshot crc 0x%08x\n", (unsigned)crc);

    /* The 64x48 view from the last frame's pose, in bands of 8 rows. */
    view.fx = cam.fx * 64.0f / (float)cam.width;
    view.fy = cam.fy * 48.0f / (float)cam.height;
    view.cx = 32.0f;
    view.cy = 24.0f;
    view.width = 64;
    view.height = 48;
    crc = 0xFFFFFFFFu;
    for (row = 0; row < 48; row += 8) {
        size_t i;
        CHECK(sndt_render(map, &pose, &view, row, labels, distance, 64 * 8));
        for (i = 0; i < 64 * 8; i++) {
            uint8_t b[4];
            uint32_t u;
            memcpy(&u, &distance[i], 4);
            b[0] = (uint8_t)u;
            b[1] = (uint8_t)(u >> 8);
            b[2] = (uint8_t)(u >> 16);
            b[3] = (uint8_t)(u >> 24);
            crc = crc32_update(crc, &labels[i], 1);
            crc = crc32_update(crc, b, 4);
        }
    }
    printf("render crc 0x%08x\n", (unsigned)~crc);
    free(depth);
    free(v);
    return 0;
}

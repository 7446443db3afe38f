/*
 * The C API's alternative inputs give the same map: depth in millimetres (uint16_t) and the
 * same depths in metres; top-k labels with one full-score label and one class per pixel;
 * a pose from a quaternion and from the equivalent 4x4 matrix; a snapshot saved and loaded
 * into a second map. Exits 0 when all agree. C99.
 */
#include <stdio.h>
#include <string.h>

#include "sndt.h"

enum { W = 16, H = 12, N = W * H };

static uint8_t a_storage[SNDT_MAP_BYTES] __attribute__((aligned(SNDT_MAP_ALIGN)));
static uint8_t b_storage[SNDT_MAP_BYTES] __attribute__((aligned(SNDT_MAP_ALIGN)));
static uint8_t snapshot[SNDT_SNAPSHOT_MAX_BYTES];

static int failures;

static void expect_ok(sndt_status s, const char *what) {
    if (s != SNDT_OK) {
        printf("FAIL %s: %s\n", what, sndt_status_str(s));
        failures++;
    }
}

static uint32_t crc_of(const sndt_map *map) {
    uint32_t crc = 0;
    expect_ok(sndt_checksum(map, &crc), "sndt_checksum");
    return crc;
}

static void same(const sndt_map *a, const sndt_map *b, const char *what) {
    uint32_t ca = crc_of(a), cb = crc_of(b);
    printf("%s: 0x%08x 0x%08x %s\n", what, (unsigned)ca, (unsigned)cb, ca == cb ? "same" : "DIFFER");
    failures += ca != cb;
}

int main(void) {
    sndt_map *a = (sndt_map *)a_storage, *b = (sndt_map *)b_storage;
    sndt_config cfg = sndt_config_default();
    uint16_t mm[N];
    float m[N];
    uint8_t top1[N];
    sndt_labels topk[N];
    sndt_pinhole cam = {20.0f, 20.0f, 8.0f, 6.0f, W, H};
    /* 30 degrees about the camera's y axis: q = (cos 15, 0, sin 15, 0), and its matrix. */
    const float q[4] = {0.96592583f, 0.0f, 0.25881905f, 0.0f}, t[3] = {0.5f, -0.2f, 1.0f};
    float m4[16];
    sndt_pose pq, pm;
    sndt_depth_frame fa, fb;
    size_t i, len = 0;
    for (i = 0; i < N; i++) {
        mm[i] = (uint16_t)(i % 17 == 0 ? 0 : 1500 + 37 * (i % 23)); /* 0: no return */
        m[i] = (float)mm[i] / 1000.0f;
        top1[i] = (uint8_t)(1 + i % 5);
        memset(&topk[i], 0, sizeof topk[i]);
        topk[i].classes[0] = top1[i];
        topk[i].scores[0] = 255;
        topk[i].len = 1;
    }
    expect_ok(sndt_pose_from_quaternion(q, t, &pq), "sndt_pose_from_quaternion");
    {
        const float w = q[0], y = q[2];
        const float r[9] = {1 - 2 * y * y, 0, 2 * w * y, 0, 1, 0, -2 * w * y, 0, 1 - 2 * y * y};
        for (i = 0; i < 3; i++) {
            memcpy(&m4[4 * i], &r[3 * i], 3 * sizeof(float));
            m4[4 * i + 3] = t[i];
        }
        m4[12] = m4[13] = m4[14] = 0.0f;
        m4[15] = 1.0f;
    }
    expect_ok(sndt_pose_from_matrix4(m4, &pm), "sndt_pose_from_matrix4");

    memset(&fa, 0, sizeof fa);
    fa.camera = cam;
    fa.stride = 1;
    fa.len = N;
    fb = fa;
    fa.depth_mm = mm;
    fa.labels = top1;
    fb.depth_m = m;
    fb.labels_topk = topk;
    expect_ok(sndt_map_init(a, sizeof a_storage, &cfg), "init a");
    expect_ok(sndt_map_init(b, sizeof b_storage, &cfg), "init b");
    expect_ok(sndt_integrate_depth(a, &pq, &fa, NULL), "integrate mm, top-1");
    expect_ok(sndt_integrate_depth(b, &pq, &fb, NULL), "integrate metres, top-k");
    same(a, b, "millimetres + top-1 vs metres + top-k");

    expect_ok(sndt_map_init(b, sizeof b_storage, &cfg), "re-init b");
    expect_ok(sndt_integrate_depth(b, &pm, &fa, NULL), "integrate with the matrix pose");
    /* The matrix's quaternion is recovered to within rounding: same map or not is a property
     * of the core's pose_from_matrix; here the two poses must at least both be valid and
     * give maps with the same number of voxels. */
    {
        sndt_stats sa, sb;
        expect_ok(sndt_map_stats(a, &sa), "stats a");
        expect_ok(sndt_map_stats(b, &sb), "stats b");
        printf("quaternion vs matrix pose: %u and %u voxels\n", (unsigned)sa.voxels, (unsigned)sb.voxels);
        failures += sa.voxels != sb.voxels || sa.voxels == 0;
    }

    expect_ok(sndt_save(a, snapshot, sizeof snapshot, &len), "save a");
    expect_ok(sndt_load(b, snapshot, len), "load into b");
    same(a, b, "saved and loaded");
    printf("paths: %d failed\n", failures);
    return failures == 0 ? 0 : 1;
}

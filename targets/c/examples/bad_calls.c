/*
 * Bad calls through the C API: each returns its documented status and leaves the map (and
 * every output) unchanged. Exits 0 when every check holds, 1 otherwise. C99.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "sndt.h"

static int failures, checks;

#define EXPECT(call, want)                                                               \
    do {                                                                                 \
        sndt_status got_ = (call);                                                       \
        checks++;                                                                        \
        if (got_ != (want)) {                                                            \
            failures++;                                                                  \
            printf("FAIL line %d: %s -> %d (%s), expected %s\n", __LINE__, #call,        \
                   (int)got_, sndt_status_str(got_), #want);                             \
        }                                                                                \
    } while (0)

#define TRUE(cond)                                                                       \
    do {                                                                                 \
        checks++;                                                                        \
        if (!(cond)) {                                                                   \
            failures++;                                                                  \
            printf("FAIL line %d: %s\n", __LINE__, #cond);                               \
        }                                                                                \
    } while (0)

/* One more byte than a map, so that storage + 1 is a misaligned pointer to enough bytes. */
static uint8_t storage[SNDT_MAP_BYTES + SNDT_MAP_ALIGN] __attribute__((aligned(SNDT_MAP_ALIGN)));
static uint8_t snapshot[SNDT_SNAPSHOT_MAX_BYTES];

enum { W = 8, H = 6, N = W * H };

static uint32_t crc_of(const sndt_map *map) {
    uint32_t crc = 0;
    EXPECT(sndt_checksum(map, &crc), SNDT_OK);
    return crc;
}

/* An 8x6 frame; 5 cm between pixels at 2 m, so 10 cm voxels get 4 points each. */
static sndt_depth_frame frame(const float *depth, const uint8_t *labels) {
    sndt_depth_frame f;
    sndt_pinhole cam = {40.0f, 40.0f, 4.0f, 3.0f, W, H};
    memset(&f, 0, sizeof f);
    f.camera = cam;
    f.depth_m = depth;
    f.labels = labels;
    f.stride = 1;
    f.len = N;
    return f;
}

static void init_checks(sndt_map *map) {
    sndt_config cfg = sndt_config_default(), bad = cfg;
    size_t i;
    TRUE(sndt_map_bytes() == SNDT_MAP_BYTES);
    /* Uninitialised (zeroed) storage is refused. */
    EXPECT(sndt_checksum(map, NULL), SNDT_ERR_NOT_INITIALISED);
    EXPECT(sndt_map_init(NULL, SNDT_MAP_BYTES, &cfg), SNDT_ERR_NULL);
    EXPECT(sndt_map_init(map, SNDT_MAP_BYTES, NULL), SNDT_ERR_NULL);
    memset(storage, 0xAB, sizeof storage);
    EXPECT(sndt_map_init(map, SNDT_MAP_BYTES - 1, &cfg), SNDT_ERR_CAPACITY);
    EXPECT(sndt_map_init((sndt_map *)(storage + 1), SNDT_MAP_BYTES, &cfg), SNDT_ERR_BAD_ARG);
    bad.cell_size = NAN;
    EXPECT(sndt_map_init(map, SNDT_MAP_BYTES, &bad), SNDT_ERR_CONFIG);
    bad = cfg;
    bad.miss_model = 7;
    EXPECT(sndt_map_init(map, SNDT_MAP_BYTES, &bad), SNDT_ERR_CONFIG);
    /* Valid numbers, but rays of more than 4096 cells: refused (work per ray is bounded). */
    bad = cfg;
    bad.max_range = 4097.0f * cfg.cell_size;
    EXPECT(sndt_map_init(map, SNDT_MAP_BYTES, &bad), SNDT_ERR_CONFIG);
    bad.miss_model = 7; /* sndt_map_config below must overwrite every field */
    for (i = 0; i < sizeof storage && storage[i] == 0xAB; i++) {
    }
    TRUE(i == sizeof storage); /* failed inits wrote nothing */
    EXPECT(sndt_checksum(map, NULL), SNDT_ERR_NOT_INITIALISED);
    EXPECT(sndt_map_init(map, SNDT_MAP_BYTES, &cfg), SNDT_OK);
    EXPECT(sndt_map_config(map, &bad), SNDT_OK);
    TRUE(memcmp(&bad, &cfg, sizeof cfg) == 0);
}

static void pose_checks(void) {
    const float t[3] = {0, 0, 0}, unit[4] = {1, 0, 0, 0}, twice[4] = {2, 0, 0, 0};
    const float nan_q[4] = {NAN, 0, 0, 0};
    float m[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    sndt_pose p, before;
    EXPECT(sndt_pose_from_quaternion(unit, t, &p), SNDT_OK);
    before = p;
    EXPECT(sndt_pose_from_quaternion(nan_q, t, &p), SNDT_ERR_BAD_ARG);
    EXPECT(sndt_pose_from_quaternion(twice, t, &p), SNDT_ERR_BAD_ARG);
    EXPECT(sndt_pose_from_quaternion(NULL, t, &p), SNDT_ERR_NULL);
    EXPECT(sndt_pose_from_quaternion(unit, t, NULL), SNDT_ERR_NULL);
    {
        /* 90 degrees about z, then a translation: R and t give the 4x4 matrix's pose. */
        const float r[9] = {0, -1, 0, 1, 0, 0, 0, 0, 1}, tr[3] = {1, 2, 3};
        const float r_bad[9] = {1, 0, 0, 0, 1, 0, 0, 0, 2};
        const float m4[16] = {0, -1, 0, 1, 1, 0, 0, 2, 0, 0, 1, 3, 0, 0, 0, 1};
        sndt_pose a, b;
        EXPECT(sndt_pose_from_rt(r, tr, &a), SNDT_OK);
        EXPECT(sndt_pose_from_matrix4(m4, &b), SNDT_OK);
        TRUE(memcmp(&a, &b, sizeof a) == 0 && a.t[2] == 3.0f);
        EXPECT(sndt_pose_from_rt(r_bad, tr, &a), SNDT_ERR_BAD_ARG);
        EXPECT(sndt_pose_from_rt(NULL, tr, &a), SNDT_ERR_NULL);
    }
    m[15] = 2.0f;
    EXPECT(sndt_pose_from_matrix4(m, &p), SNDT_ERR_BAD_ARG);
    m[15] = 1.0f;
    m[0] = 3.0f; /* not a rotation */
    EXPECT(sndt_pose_from_matrix4(m, &p), SNDT_ERR_BAD_ARG);
    m[0] = 1.0f;
    m[3] = INFINITY;
    EXPECT(sndt_pose_from_matrix4(m, &p), SNDT_ERR_BAD_ARG);
    TRUE(memcmp(&p, &before, sizeof p) == 0); /* outputs untouched on errors */
}

static void integrate_checks(sndt_map *map, const sndt_pose *pose) {
    float depth[N], nan_depth[N];
    uint8_t labels[N];
    sndt_depth_frame f, g;
    sndt_frame_report r;
    sndt_pose nan_pose = *pose;
    uint32_t crc;
    size_t i;
    sndt_point pts[2];
    for (i = 0; i < N; i++) {
        depth[i] = 2.05f; /* a wall 2.05 m ahead, class 7 */
        nan_depth[i] = NAN;
        labels[i] = 7;
    }
    f = frame(depth, labels);
    EXPECT(sndt_integrate_depth(map, pose, &f, &r), SNDT_OK);
    TRUE(r.points_used == N);
    crc = crc_of(map);
    nan_pose.q[0] = NAN;
    EXPECT(sndt_integrate_depth(map, &nan_pose, &f, &r), SNDT_ERR_BAD_ARG);
    nan_pose = *pose;
    nan_pose.t[2] = INFINITY;
    EXPECT(sndt_integrate_depth(map, &nan_pose, &f, &r), SNDT_ERR_BAD_ARG);
    nan_pose.t[2] = 1e6f; /* finite, but outside the key range */
    EXPECT(sndt_integrate_depth(map, &nan_pose, &f, &r), SNDT_ERR_OUT_OF_RANGE);
    EXPECT(sndt_integrate_depth(map, pose, NULL, &r), SNDT_ERR_NULL);
    EXPECT(sndt_integrate_depth(NULL, pose, &f, &r), SNDT_ERR_NULL);
    g = f;
    g.len = N - 1; /* buffers smaller than the camera says */
    EXPECT(sndt_integrate_depth(map, pose, &g, &r), SNDT_ERR_BAD_ARG);
    g = f;
    g.camera.fx = 0.0f;
    EXPECT(sndt_integrate_depth(map, pose, &g, &r), SNDT_ERR_BAD_ARG);
    g = f;
    g.depth_m = NULL;
    EXPECT(sndt_integrate_depth(map, pose, &g, &r), SNDT_ERR_BAD_ARG);
    g = f;
    g.depth_mm = (const uint16_t *)labels; /* both depth kinds */
    EXPECT(sndt_integrate_depth(map, pose, &g, &r), SNDT_ERR_BAD_ARG);
    g = f;
    g.stride = 0;
    EXPECT(sndt_integrate_depth(map, pose, &g, &r), SNDT_ERR_BAD_ARG);
    g = f;
    g.range = 2;
    EXPECT(sndt_integrate_depth(map, pose, &g, &r), SNDT_ERR_BAD_ARG);
    TRUE(crc_of(map) == crc);
    /* Bad pixels are counted, not errors. */
    g = frame(nan_depth, labels);
    EXPECT(sndt_integrate_depth(map, pose, &g, &r), SNDT_OK);
    TRUE(r.rejected_depth == N && r.points_used == 0);
    memset(pts, 0, sizeof pts);
    pts[0].xyz[2] = 2.0f;
    pts[0].labels.classes[0] = SNDT_CLASSES + 1; /* out of range: rejected */
    pts[0].labels.len = 1;
    pts[1].xyz[2] = NAN;
    EXPECT(sndt_integrate_points(map, pose, pts, 2, &r), SNDT_OK);
    TRUE(r.rejected_label == 1 && r.rejected_depth == 1 && r.points_used == 0);
    EXPECT(sndt_integrate_points(map, pose, NULL, 2, &r), SNDT_ERR_NULL);
}

static void query_checks(const sndt_map *map, const sndt_pose *pose) {
    const float at[3] = {0.03f, 0.03f, 2.05f}, far[3] = {1e9f, 0, 0}, nan_p[3] = {NAN, 0, 0};
    const float dir[3] = {0.0125f, 0.0125f, 1}, zero[3] = {0, 0, 0};
    sndt_query q;
    sndt_ray_hit hit;
    uint8_t labels[W * H];
    float distance[W * H];
    sndt_pinhole cam = {40.0f, 40.0f, 4.0f, 3.0f, W, H};
    EXPECT(sndt_query_point(map, at, &q), SNDT_OK);
    TRUE(q.occupancy == 2 && q.class_id == 7 && q.probability > 0.5f);
    EXPECT(sndt_query_point(map, far, &q), SNDT_ERR_OUT_OF_RANGE);
    EXPECT(sndt_query_point(map, nan_p, &q), SNDT_ERR_BAD_ARG);
    EXPECT(sndt_raycast(map, zero, dir, 10.0f, &hit), SNDT_OK);
    TRUE(hit.hit == 1 && hit.class_id == 7 && fabsf(hit.t - 2.05f) < 0.1f);
    EXPECT(sndt_raycast(map, zero, zero, 10.0f, &hit), SNDT_ERR_BAD_ARG);
    EXPECT(sndt_raycast(map, zero, dir, NAN, &hit), SNDT_ERR_BAD_ARG);
    EXPECT(sndt_render(map, pose, &cam, 0, labels, distance, W * H), SNDT_OK);
    TRUE(labels[3 * W + 4] == 7 && fabsf(distance[3 * W + 4] - 2.05f) < 0.1f);
    EXPECT(sndt_render(map, pose, &cam, 0, labels, distance, W * H - 1), SNDT_ERR_BAD_ARG);
    EXPECT(sndt_render(map, pose, &cam, 5, labels, distance, 2 * W), SNDT_ERR_BAD_ARG);
    EXPECT(sndt_render(map, pose, &cam, 0, NULL, distance, W * H), SNDT_ERR_NULL);
    EXPECT(sndt_render(map, pose, &cam, 0, labels, (float *)(labels + 1), 4), SNDT_ERR_BAD_ARG);
    /* Overlapping buffers (aligned, so only the overlap is wrong): refused. */
    EXPECT(sndt_render(map, pose, &cam, 0, (uint8_t *)distance, distance, W * H), SNDT_ERR_BAD_ARG);
    EXPECT(sndt_render(map, pose, &cam, 0, labels, (float *)storage, W * H), SNDT_ERR_BAD_ARG);
}

static void snapshot_checks(sndt_map *map) {
    size_t len = 0, written = 0;
    uint32_t crc = crc_of(map);
    EXPECT(sndt_snapshot_len(map, &len), SNDT_OK);
    TRUE(len > 0 && len <= sizeof snapshot);
    memset(snapshot, 0x5A, sizeof snapshot);
    EXPECT(sndt_save(map, snapshot, len - 1, &written), SNDT_ERR_BUFFER_TOO_SMALL);
    TRUE(written == 0 && snapshot[0] == 0x5A);
    EXPECT(sndt_save(map, snapshot, sizeof snapshot, &written), SNDT_OK);
    TRUE(written == len);
    snapshot[len / 2] ^= 0x01; /* the CRC catches it */
    EXPECT(sndt_load(map, snapshot, len), SNDT_ERR_CORRUPT);
    snapshot[len / 2] ^= 0x01;
    EXPECT(sndt_load(map, snapshot, len - 1), SNDT_ERR_CORRUPT);
    EXPECT(sndt_load(map, snapshot, 0), SNDT_ERR_CORRUPT);
    EXPECT(sndt_load(map, NULL, len), SNDT_ERR_NULL);
    EXPECT(sndt_save(map, storage + 64, len, &written), SNDT_ERR_BAD_ARG); /* into the map */
    EXPECT(sndt_load(map, storage + 64, len), SNDT_ERR_BAD_ARG);
    snapshot[8] ^= 0x7F; /* the version */
    EXPECT(sndt_load(map, snapshot, len), SNDT_ERR_CORRUPT);
    snapshot[8] ^= 0x7F;
    TRUE(crc_of(map) == crc);
    EXPECT(sndt_load(map, snapshot, len), SNDT_OK);
    TRUE(crc_of(map) == crc);
}

int main(void) {
    sndt_map *map = (sndt_map *)storage;
    const float t[3] = {0, 0, 0}, unit[4] = {1, 0, 0, 0};
    sndt_pose pose;
    int code;
    init_checks(map);
    pose_checks();
    EXPECT(sndt_pose_from_quaternion(unit, t, &pose), SNDT_OK);
    integrate_checks(map, &pose);
    query_checks(map, &pose);
    snapshot_checks(map);
    for (code = 0; code <= SNDT_ERR_INCOMPATIBLE; code++) TRUE(strlen(sndt_status_str(code)) > 0);
    TRUE(strcmp(sndt_status_str(999), "unknown status") == 0);
    printf("bad_calls: %d checks, %d failed\n", checks, failures);
    return failures == 0 ? 0 : 1;
}

/*
 * Bare-metal C firmware for Cortex-M4F (QEMU mps2-an386) over the sndt C API (sndt.h,
 * libsndt_c.a): the C twin of targets/cortex-m4f (Rust), built by scripts/c-firmware.sh.
 *
 * Integrates the committed test vector (targets/cortex-m4f/vector/frames.bin: 4 labelled
 * 160x120 depth frames, embedded in flash by vector.S) into a map in a static .bss array,
 * prints each frame's report, the map's snapshot CRC and counts, renders a 64x48 view from
 * the last frame's pose in bands of 8 rows and prints the view's CRC-32. Both CRCs must equal
 * the host's (expected_crc.txt and expected_render_crc.txt, passed in as -DEXPECTED_CRC and
 * -DEXPECTED_RENDER_CRC). Output goes through picolibc's semihosting stdio; the exit status
 * (semihosting) is 0 only when every check passes. Also reports SysTick ticks per frame
 * (QEMU -icount shift=0: 40 instructions per tick) and the peak stack (painted region).
 */
#include <inttypes.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sndt.h"

#if !defined(EXPECTED_CRC) || !defined(EXPECTED_RENDER_CRC)
#error "compile with -DEXPECTED_CRC=0x... -DEXPECTED_RENDER_CRC=0x... (targets/cortex-m4f/vector/*.txt)"
#endif

/* The map: the library's storage, zero-initialised (.bss, no flash copy). */
static uint8_t map_storage[SNDT_MAP_BYTES] __attribute__((aligned(SNDT_MAP_ALIGN)));

/* The test vector in flash (vector.S), 4-byte aligned. */
extern const uint8_t sndt_vector[];
extern const uint8_t sndt_vector_end[];

/* picolibc.ld: start of RAM data, end of .bss (heap start), bottom of the stack budget,
 * initial stack pointer. */
extern uint8_t __data_start[];
extern uint8_t __heap_start[];
extern uint8_t __heap_end[];
extern uint8_t __stack[];

/* ---- Test vector (format: host/src/embedded/testvector.rs, version 1, little-endian) ---- */

#define VEC_HEADER_BYTES 56u
#define VEC_PROBE_BYTES 8u
#define VEC_POSE_BYTES 48u

static uint16_t rd_u16(const uint8_t *b) { return (uint16_t)(b[0] | (b[1] << 8)); }

static uint32_t rd_u32(const uint8_t *b)
{
    return (uint32_t)b[0] | ((uint32_t)b[1] << 8) | ((uint32_t)b[2] << 16) | ((uint32_t)b[3] << 24);
}

static float rd_f32(const uint8_t *b)
{
    uint32_t bits = rd_u32(b);
    float f;
    memcpy(&f, &bits, sizeof f);
    return f;
}

/* A parsed vector: its camera, cell size and frames. */
struct vector {
    const uint8_t *bytes;
    unsigned frames;
    unsigned probes;
    sndt_pinhole camera;
    float cell_size;
    size_t frame_bytes; /* pose + W*H f32 depths + W*H u8 labels */
};

/* One frame, borrowed from flash. */
struct frame {
    float pose[16]; /* row-major [R | t; 0 0 0 1], camera-to-world */
    const float *depth;
    const uint8_t *labels;
};

/* Checks the vector's header against the library's capacities and its total length. */
static int vector_parse(struct vector *v)
{
    const uint8_t *b = sndt_vector;
    size_t len = (size_t)((uintptr_t)sndt_vector_end - (uintptr_t)sndt_vector);
    size_t n;

    if (len < VEC_HEADER_BYTES || memcmp(b, "SNDTVEC\0", 8) != 0) {
        printf("test vector: bad magic or size\n");
        return 0;
    }
    if (rd_u16(b + 8) != 1) {
        printf("test vector: version %u, expected 1\n", (unsigned)rd_u16(b + 8));
        return 0;
    }
    if (rd_u16(b + 14) != SNDT_CLASSES || rd_u32(b + 16) != SNDT_VOXELS || rd_u32(b + 20) != SNDT_BLOCKS) {
        printf("test vector: capacities %u/%" PRIu32 "/%" PRIu32 ", firmware %u/%u/%u (classes/voxels/blocks)\n",
               (unsigned)rd_u16(b + 14), rd_u32(b + 16), rd_u32(b + 20), (unsigned)SNDT_CLASSES,
               (unsigned)SNDT_VOXELS, (unsigned)SNDT_BLOCKS);
        return 0;
    }
    v->bytes = b;
    v->frames = rd_u16(b + 10);
    v->probes = rd_u16(b + 12);
    v->camera.width = rd_u32(b + 24);
    v->camera.height = rd_u32(b + 28);
    v->camera.fx = rd_f32(b + 32);
    v->camera.fy = rd_f32(b + 36);
    v->camera.cx = rd_f32(b + 40);
    v->camera.cy = rd_f32(b + 44);
    v->cell_size = rd_f32(b + 48);
    n = (size_t)v->camera.width * v->camera.height;
    v->frame_bytes = VEC_POSE_BYTES + 5u * n;
    if (v->frames == 0 || n % 4 != 0 ||
        len != VEC_HEADER_BYTES + VEC_PROBE_BYTES * v->probes + v->frames * v->frame_bytes) {
        printf("test vector: length %zu disagrees with its header\n", len);
        return 0;
    }
    return 1;
}

/* Frame k (< v->frames): its 4x4 pose and its images, in place in flash. */
static int vector_frame(const struct vector *v, unsigned k, struct frame *f)
{
    const uint8_t *o = v->bytes + VEC_HEADER_BYTES + VEC_PROBE_BYTES * v->probes + k * v->frame_bytes;
    const uint8_t *d = o + VEC_POSE_BYTES;
    unsigned i;

    for (i = 0; i < 3; i++) {
        f->pose[4 * i + 0] = rd_f32(o + 4 * (3 * i + 0));
        f->pose[4 * i + 1] = rd_f32(o + 4 * (3 * i + 1));
        f->pose[4 * i + 2] = rd_f32(o + 4 * (3 * i + 2));
        f->pose[4 * i + 3] = rd_f32(o + 36 + 4 * i);
    }
    f->pose[12] = 0.0f;
    f->pose[13] = 0.0f;
    f->pose[14] = 0.0f;
    f->pose[15] = 1.0f;
    if ((uintptr_t)d % 4 != 0) {
        printf("frame %u: depth image not 4-byte aligned\n", k);
        return 0;
    }
    /* The target is little-endian: the bytes are the floats (the library checks alignment too). */
    f->depth = (const float *)(const void *)d;
    f->labels = d + 4u * (size_t)v->camera.width * v->camera.height;
    return 1;
}

/* ---- SysTick: a free-running 24-bit down-counter on the core clock (no interrupt) ---- */

#define SYST_CSR (*(volatile uint32_t *)0xE000E010u)
#define SYST_RVR (*(volatile uint32_t *)0xE000E014u)
#define SYST_CVR (*(volatile uint32_t *)0xE000E018u)
#define SYST_COUNTFLAG (1u << 16)

static void systick_start(void)
{
    SYST_RVR = 0x00FFFFFFu;
    SYST_CVR = 0; /* any write clears the counter and COUNTFLAG */
    SYST_CSR = 5u; /* ENABLE | CLKSOURCE = core */
}

/* Reading CSR clears COUNTFLAG: call before a measurement. */
static uint32_t systick_now(void)
{
    (void)SYST_CSR;
    return SYST_CVR;
}

/* Ticks since `start`, or UINT32_MAX if the counter wrapped (more than 2^24 ticks). */
static uint32_t systick_since(uint32_t start)
{
    uint32_t now = SYST_CVR;
    if (SYST_CSR & SYST_COUNTFLAG)
        return UINT32_MAX;
    return (start - now) & 0x00FFFFFFu;
}

/* ---- Stack painting ---- */

#define STACK_PAINT 0xA5C3A5C3u
/* Stack headroom that must stay unused. */
#define STACK_MARGIN 256u

/* Fills RAM from the end of .bss to just below this function's frame with STACK_PAINT. */
static void __attribute__((noinline)) stack_paint(void)
{
    uintptr_t sp, p;
    __asm__ __volatile__("mov %0, sp" : "=r"(sp));
    for (p = (uintptr_t)__heap_start; p + 4 <= sp - 64; p += 4)
        *(volatile uint32_t *)p = STACK_PAINT;
}

/* Deepest stack use so far: from the initial stack pointer down to the lowest unpainted word. */
static size_t stack_peak(void)
{
    uintptr_t p = (uintptr_t)__heap_start;
    while (p < (uintptr_t)__stack && *(volatile const uint32_t *)p == STACK_PAINT)
        p += 4;
    return (size_t)((uintptr_t)__stack - p);
}

/* ---- CRC-32 (IEEE 802.3: reflected, polynomial 0xEDB88320), bitwise ---- */

static uint32_t crc32_update(uint32_t crc, const uint8_t *p, size_t n)
{
    while (n--) {
        unsigned bit;
        crc ^= *p++;
        for (bit = 0; bit < 8; bit++)
            crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
    }
    return crc;
}

/* ---- The run ---- */

static int check(sndt_status s, const char *what)
{
    if (s != SNDT_OK)
        printf("%s: %s\n", what, sndt_status_str((int32_t)s));
    return s == SNDT_OK;
}

/* Integrates every frame; 0 if a call failed or a frame had points rejected. */
static int integrate_frames(sndt_map *map, const struct vector *v)
{
    uint32_t total_ticks = 0;
    unsigned k;
    int ok = 1;

    for (k = 0; k < v->frames; k++) {
        struct frame f;
        sndt_pose pose;
        sndt_depth_frame image;
        sndt_frame_report rep;
        uint32_t start, ticks;
        sndt_status s;

        if (!vector_frame(v, k, &f) || !check(sndt_pose_from_matrix4(f.pose, &pose), "frame pose"))
            return 0;
        memset(&image, 0, sizeof image);
        image.camera = v->camera;
        image.depth_m = f.depth;   /* planar depth in metres */
        image.depth_mm = NULL;
        image.range = 0;           /* along the optical axis */
        image.labels = f.labels;   /* top-1 class ids */
        image.labels_topk = NULL;
        image.stride = 1;
        image.len = (size_t)v->camera.width * v->camera.height; /* entries per image buffer */

        start = systick_now();
        s = sndt_integrate_depth(map, &pose, &image, &rep);
        ticks = systick_since(start);
        if (!check(s, "sndt_integrate_depth")) {
            ok = 0;
            continue;
        }
        total_ticks += ticks == UINT32_MAX ? 0 : ticks;
        printf("frame %u: points %" PRIu32 ", end voxels %" PRIu32 ", rays %" PRIu32 ", voxels +%" PRIu32
               " -%" PRIu32 ", blocks +%" PRIu32 " -%" PRIu32 ", dropped %" PRIu32 "/%" PRIu32
               ", systick %" PRIu32 "\n",
               k, rep.points_used, rep.end_voxels, rep.rays, rep.voxels_created, rep.voxels_evicted,
               rep.blocks_created, rep.blocks_evicted, rep.dropped_points, rep.dropped_misses, ticks);
        if (rep.rejected_label != 0 || rep.rejected_out_of_range != 0) {
            printf("frame %u: points were rejected\n", k);
            ok = 0;
        }
    }
    printf("systick per frame %" PRIu32 " (mean over %u frames)\n", total_ticks / v->frames, v->frames);
    return ok;
}

/* Prints the map's counts and checks its snapshot CRC. */
static int check_map(const sndt_map *map, const struct vector *v)
{
    sndt_stats st;
    uint32_t crc;

    if (!check(sndt_map_stats(map, &st), "sndt_map_stats") || !check(sndt_checksum(map, &crc), "sndt_checksum"))
        return 0;
    printf("voxels %" PRIu32 " of %" PRIu32 ", blocks %" PRIu32 " of %" PRIu32 ", frames %" PRIu32
           ", evictions: voxels %lu blocks %lu\n",
           st.voxels, st.voxel_capacity, st.blocks, st.block_capacity, st.frames,
           (unsigned long)st.voxels_evicted, (unsigned long)st.blocks_evicted);
    printf("snapshot crc 0x%08" PRIx32 "\n", crc);
    if (crc != (uint32_t)EXPECTED_CRC) {
        printf("snapshot crc MISMATCH: expected 0x%08" PRIx32 "\n", (uint32_t)EXPECTED_CRC);
        return 0;
    }
    return st.frames == v->frames;
}

#define VIEW_W 64u
#define VIEW_H 48u
#define BAND_ROWS 8u
#define BAND_PIXELS (VIEW_W * BAND_ROWS)

/* Renders a 64x48 view from the last frame's pose and checks the CRC of its pixels (each
 * pixel's label byte, then its distance's 4 little-endian bytes, row-major). */
static int check_view(const sndt_map *map, const struct vector *v)
{
    uint8_t labels[BAND_PIXELS];
    float distance[BAND_PIXELS];
    uint32_t hist[SNDT_CLASSES + 2] = {0}; /* per class; [SNDT_CLASSES + 1]: no hit */
    uint32_t crc = 0xFFFFFFFFu, row, ticks = 0;
    struct frame f;
    sndt_pose pose;
    sndt_pinhole cam;
    unsigned i;

    if (!vector_frame(v, v->frames - 1, &f) || !check(sndt_pose_from_matrix4(f.pose, &pose), "view pose"))
        return 0;
    /* The vector's camera scaled to 64x48 (the same float operations as the host). */
    cam.fx = v->camera.fx * 64.0f / (float)v->camera.width;
    cam.fy = v->camera.fy * 48.0f / (float)v->camera.height;
    cam.cx = 32.0f;
    cam.cy = 24.0f;
    cam.width = VIEW_W;
    cam.height = VIEW_H;

    for (row = 0; row < VIEW_H; row += BAND_ROWS) {
        uint32_t start = systick_now(), t;
        sndt_status s = sndt_render(map, &pose, &cam, row, labels, distance, BAND_PIXELS);
        t = systick_since(start);
        ticks = ticks == UINT32_MAX || t == UINT32_MAX ? UINT32_MAX : ticks + t;
        if (!check(s, "sndt_render"))
            return 0;
        for (i = 0; i < BAND_PIXELS; i++) {
            uint32_t bits;
            uint8_t le[4];
            unsigned bin = labels[i] == SNDT_NO_HIT ? SNDT_CLASSES + 1
                           : labels[i] > SNDT_CLASSES ? SNDT_CLASSES
                                                      : labels[i];
            hist[bin]++;
            memcpy(&bits, &distance[i], sizeof bits);
            le[0] = (uint8_t)bits;
            le[1] = (uint8_t)(bits >> 8);
            le[2] = (uint8_t)(bits >> 16);
            le[3] = (uint8_t)(bits >> 24);
            crc = crc32_update(crc, &labels[i], 1);
            crc = crc32_update(crc, le, 4);
        }
    }
    crc ^= 0xFFFFFFFFu;
    for (i = 0; i < SNDT_CLASSES + 2; i++) {
        if (hist[i] == 0)
            continue;
        if (i == SNDT_CLASSES + 1)
            printf("view: no hit %" PRIu32 " pixels\n", hist[i]);
        else
            printf("view: class %u %" PRIu32 " pixels\n", i, hist[i]);
    }
    printf("view %ux%u from frame %u: systick %" PRIu32 " (%u bands of %u rows)\n", VIEW_W, VIEW_H, v->frames - 1, ticks,
           VIEW_H / BAND_ROWS, BAND_ROWS);
    printf("render crc 0x%08" PRIx32 "\n", crc);
    if (crc != (uint32_t)EXPECTED_RENDER_CRC) {
        printf("render crc MISMATCH: expected 0x%08" PRIx32 "\n", (uint32_t)EXPECTED_RENDER_CRC);
        return 0;
    }
    return 1;
}

/* Peak stack of each phase (the stack is repainted between phases). */
struct stack_peaks {
    size_t setup, integrate, map, view;
};

/* Everything but the stack check; 1 when every check passes. */
static int __attribute__((noinline)) run(struct stack_peaks *peaks)
{
    sndt_map *map = (sndt_map *)(void *)map_storage;
    sndt_config config;
    struct vector v;
    int ok;

    if (sndt_map_bytes() != SNDT_MAP_BYTES) {
        printf("sndt_map_bytes() = %zu, header SNDT_MAP_BYTES = %zu: capacities differ\n", sndt_map_bytes(),
               (size_t)SNDT_MAP_BYTES);
        return 0;
    }
    if (!vector_parse(&v))
        return 0;
    config = sndt_config_default();
    config.cell_size = v.cell_size;
    if (!check(sndt_map_init(map, sizeof map_storage, &config), "sndt_map_init"))
        return 0;
    printf("map: %u voxels, %u blocks, %u classes = %zu bytes; vector: %u frames of %" PRIu32 "x%" PRIu32
           ", cell %" PRIu32 " mm\n",
           (unsigned)SNDT_VOXELS, (unsigned)SNDT_BLOCKS, (unsigned)SNDT_CLASSES, (size_t)SNDT_MAP_BYTES, v.frames,
           v.camera.width, v.camera.height, (uint32_t)(v.cell_size * 1000.0f + 0.5f));

    peaks->setup = stack_peak();
    stack_paint();
    ok = integrate_frames(map, &v);
    peaks->integrate = stack_peak();
    stack_paint();
    ok &= check_map(map, &v);
    peaks->map = stack_peak();
    stack_paint();
    ok &= check_view(map, &v);
    peaks->view = stack_peak();
    return ok;
}

int main(void)
{
    size_t stack_budget = (size_t)((uintptr_t)__stack - (uintptr_t)__heap_end);
    size_t static_ram = (size_t)((uintptr_t)__heap_start - (uintptr_t)__data_start);
    struct stack_peaks peaks = {0, 0, 0, 0};
    size_t peak;
    int ok;

    stack_paint();
    systick_start();
    ok = run(&peaks);
    /* The deepest phase (run repaints between its phases; a failed run may stop early). */
    peak = stack_peak();
    peak = peaks.setup > peak ? peaks.setup : peak;
    peak = peaks.integrate > peak ? peaks.integrate : peak;
    peak = peaks.map > peak ? peaks.map : peak;
    peak = peaks.view > peak ? peaks.view : peak;
    printf("stack peaks: setup %zu, integrate %zu, stats+checksum %zu, render %zu bytes\n", peaks.setup,
           peaks.integrate, peaks.map, peaks.view);
    printf("static RAM %zu bytes, peak stack %zu bytes (of %zu)\n", static_ram, peak, stack_budget);
    if (peak + STACK_MARGIN > stack_budget) {
        printf("the stack came within %u bytes of its budget\n", STACK_MARGIN);
        ok = 0;
    }
    printf("sndt c firmware: %s\n", ok ? "PASS" : "FAIL");
    exit(ok ? 0 : 1);
}

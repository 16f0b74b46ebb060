/* Traces a ray file through Embree 4 on one thread, the way a renderer calls it.
 *
 * embree_compare.py compiles this (cc -O2 embree_rays.c -ldl) and runs it on meshtrace's
 * triangle and ray files. It loads the Embree 4 library that the embreex wheel bundles
 * (dlopen: the wheel has no headers, so the few declarations needed are below, with the
 * layouts of Embree 4's rtcore_ray.h and rtcore_common.h), builds one triangle mesh and
 * times, on the same rays:
 *
 *   default   rtcIntersect1 / rtcOccluded1 on a scene built as Mitsuba 3 builds its
 *             scenes: rtcSetSceneBuildQuality(HIGH), no scene flags. The measure.
 *   robust    the same with RTC_SCENE_FLAG_ROBUST (what the embreex bindings set), for
 *             reference: Embree's mode that avoids optimisations lowering accuracy.
 *   packet8   rtcIntersect8 / rtcOccluded8 on the default scene, consecutive rays in a
 *   packet16  packet: what Mitsuba's LLVM variant calls (8 lanes with AVX2, 16 with
 *             AVX-512).
 *
 * Usage: embree_rays LIBEMBREE4 TRIANGLES RAYS closest|any REPEATS BUILD_THREADS
 *        BUILD_REPEATS OUT
 * TRIANGLES: float32, 9 a triangle; RAYS: float32, 8 a ray (origin, t_max, unit
 * direction, 0). OUT receives, per ray, the default scene's hit distance (closest; +inf
 * for a miss) or 1/0 (any: occluded or not), float32. Prints one JSON object to stdout:
 * the timed seconds of each mode (after one warm-up), the seconds of BUILD_REPEATS timed
 * builds (after one warm-up; none for 0), and for each other mode the number of rays whose
 * result differs from the default mode's.
 */
#include <dlfcn.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* --- Embree 4's C API: the declarations used here ---------------------------------- */
typedef struct RTCDeviceTy *RTCDevice;
typedef struct RTCSceneTy *RTCScene;
typedef struct RTCGeometryTy *RTCGeometry;
#define RTC_INVALID_GEOMETRY_ID ((unsigned)-1)
enum { RTC_GEOMETRY_TYPE_TRIANGLE = 0 };
enum { RTC_BUFFER_TYPE_INDEX = 0, RTC_BUFFER_TYPE_VERTEX = 1 };
enum { RTC_FORMAT_UINT3 = 0x5003, RTC_FORMAT_FLOAT3 = 0x9003 };
enum { RTC_SCENE_FLAG_NONE = 0, RTC_SCENE_FLAG_ROBUST = 1 << 2 };
enum { RTC_BUILD_QUALITY_HIGH = 2 };
enum { RTC_DEVICE_PROPERTY_VERSION = 0, RTC_DEVICE_PROPERTY_VERSION_MAJOR = 1 };

struct __attribute__((aligned(16))) RTCRay {
    float org_x, org_y, org_z, tnear, dir_x, dir_y, dir_z, time, tfar;
    unsigned mask, id, flags;
};
/* instID and instPrimID have RTC_MAX_INSTANCE_LEVEL_COUNT (1 in the wheel's build)
 * entries; the padding keeps a build with more levels from writing past the struct. */
struct RTCHit {
    float Ng_x, Ng_y, Ng_z, u, v;
    unsigned primID, geomID, instID[1], instPrimID[1], pad[14];
};
struct __attribute__((aligned(16))) RTCRayHit {
    struct RTCRay ray;
    struct RTCHit hit;
};
#define PACKET(N)                                                                          \
    struct __attribute__((aligned(64))) RTCRay##N {                                        \
        float org_x[N], org_y[N], org_z[N], tnear[N], dir_x[N], dir_y[N], dir_z[N],         \
            time[N], tfar[N];                                                              \
        unsigned mask[N], id[N], flags[N];                                                 \
    };                                                                                     \
    struct __attribute__((aligned(64))) RTCHit##N {                                        \
        float Ng_x[N], Ng_y[N], Ng_z[N], u[N], v[N];                                       \
        unsigned primID[N], geomID[N], instID[1][N], instPrimID[1][N], pad[14][N];         \
    };                                                                                     \
    struct __attribute__((aligned(64))) RTCRayHit##N {                                     \
        struct RTCRay##N ray;                                                              \
        struct RTCHit##N hit;                                                              \
    };
PACKET(8)
PACKET(16)

static struct {
    RTCDevice (*newDevice)(const char *);
    ssize_t (*getDeviceProperty)(RTCDevice, int);
    int (*getDeviceError)(RTCDevice);
    RTCScene (*newScene)(RTCDevice);
    void (*setSceneFlags)(RTCScene, int);
    void (*setSceneBuildQuality)(RTCScene, int);
    RTCGeometry (*newGeometry)(RTCDevice, int);
    void *(*setNewGeometryBuffer)(RTCGeometry, int, unsigned, int, size_t, size_t);
    void (*commitGeometry)(RTCGeometry);
    unsigned (*attachGeometry)(RTCScene, RTCGeometry);
    void (*releaseGeometry)(RTCGeometry);
    void (*commitScene)(RTCScene);
    void (*releaseScene)(RTCScene);
    void (*intersect1)(RTCScene, struct RTCRayHit *, void *);
    void (*occluded1)(RTCScene, struct RTCRay *, void *);
    void (*intersect8)(const int *, RTCScene, struct RTCRayHit8 *, void *);
    void (*occluded8)(const int *, RTCScene, struct RTCRay8 *, void *);
    void (*intersect16)(const int *, RTCScene, struct RTCRayHit16 *, void *);
    void (*occluded16)(const int *, RTCScene, struct RTCRay16 *, void *);
} rtc;

static void die(const char *what, const char *detail) {
    fprintf(stderr, "embree_rays: %s%s%s\n", what, detail ? ": " : "", detail ? detail : "");
    exit(1);
}

static void load_api(const char *path) {
    void *lib = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!lib) die("cannot load Embree", dlerror());
#define SYM(field, name)                                                                   \
    do {                                                                                   \
        *(void **)&rtc.field = dlsym(lib, name);                                           \
        if (!rtc.field) die("Embree lacks", name);                                         \
    } while (0)
    SYM(newDevice, "rtcNewDevice");
    SYM(getDeviceProperty, "rtcGetDeviceProperty");
    SYM(getDeviceError, "rtcGetDeviceError");
    SYM(newScene, "rtcNewScene");
    SYM(setSceneFlags, "rtcSetSceneFlags");
    SYM(setSceneBuildQuality, "rtcSetSceneBuildQuality");
    SYM(newGeometry, "rtcNewGeometry");
    SYM(setNewGeometryBuffer, "rtcSetNewGeometryBuffer");
    SYM(commitGeometry, "rtcCommitGeometry");
    SYM(attachGeometry, "rtcAttachGeometry");
    SYM(releaseGeometry, "rtcReleaseGeometry");
    SYM(commitScene, "rtcCommitScene");
    SYM(releaseScene, "rtcReleaseScene");
    SYM(intersect1, "rtcIntersect1");
    SYM(occluded1, "rtcOccluded1");
    SYM(intersect8, "rtcIntersect8");
    SYM(occluded8, "rtcOccluded8");
    SYM(intersect16, "rtcIntersect16");
    SYM(occluded16, "rtcOccluded16");
#undef SYM
}

static float *read_floats(const char *path, size_t per_row, size_t *rows) {
    FILE *f = fopen(path, "rb");
    if (!f) die("cannot open", path);
    fseek(f, 0, SEEK_END);
    long bytes = ftell(f);
    fseek(f, 0, SEEK_SET);
    if (bytes <= 0 || bytes % (long)(4 * per_row)) die("not a whole number of rows", path);
    float *data = malloc((size_t)bytes);
    if (!data || fread(data, 1, (size_t)bytes, f) != (size_t)bytes) die("cannot read", path);
    fclose(f);
    *rows = (size_t)bytes / (4 * per_row);
    return data;
}

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static const float *tris;
static size_t ntris;
static RTCDevice device;

static RTCScene build(int flags) {
    RTCScene scene = rtc.newScene(device);
    rtc.setSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
    rtc.setSceneFlags(scene, flags);
    RTCGeometry g = rtc.newGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    float *v = rtc.setNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12,
                                        3 * ntris);
    unsigned *ix = rtc.setNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12,
                                            ntris);
    if (!v || !ix) die("Embree could not allocate the buffers", NULL);
    memcpy(v, tris, 36 * ntris);
    for (size_t i = 0; i < 3 * ntris; i++) ix[i] = (unsigned)i;
    rtc.commitGeometry(g);
    rtc.attachGeometry(scene, g);
    rtc.releaseGeometry(g);
    rtc.commitScene(scene);
    if (rtc.getDeviceError(device)) die("Embree reported an error building the scene", NULL);
    return scene;
}

static const float *rays;
static size_t nrays;
static int any_hit;

/* One ray's result: the hit distance (+inf for a miss) or 1/0 for occluded. */
static void trace_single(RTCScene scene, float *out) {
    for (size_t i = 0; i < nrays; i++) {
        const float *r = rays + 8 * i;
        struct RTCRayHit rh;
        struct RTCRay *ray = &rh.ray;
        ray->org_x = r[0], ray->org_y = r[1], ray->org_z = r[2], ray->tnear = 0.0f;
        ray->dir_x = r[4], ray->dir_y = r[5], ray->dir_z = r[6], ray->time = 0.0f;
        ray->tfar = r[3], ray->mask = ~0u, ray->id = 0, ray->flags = 0;
        if (any_hit) {
            rtc.occluded1(scene, ray, NULL);
            out[i] = ray->tfar == -INFINITY ? 1.0f : 0.0f;
        } else {
            rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
            rtc.intersect1(scene, &rh, NULL);
            out[i] = rh.hit.geomID == RTC_INVALID_GEOMETRY_ID ? INFINITY : ray->tfar;
        }
    }
}

/* Packets of W consecutive rays; the last one padded with inactive lanes. */
#define TRACE_PACKET(W)                                                                    \
    static void trace_packet##W(RTCScene scene, float *out) {                              \
        int valid[W];                                                                      \
        struct RTCRayHit##W rh;                                                            \
        struct RTCRay##W *ray = &rh.ray;                                                   \
        for (size_t b = 0; b < nrays; b += W) {                                            \
            size_t n = nrays - b < W ? nrays - b : W;                                      \
            for (size_t k = 0; k < W; k++) {                                               \
                const float *r = rays + 8 * (b + (k < n ? k : n - 1));                     \
                valid[k] = k < n ? -1 : 0;                                                 \
                ray->org_x[k] = r[0], ray->org_y[k] = r[1], ray->org_z[k] = r[2];          \
                ray->tnear[k] = 0.0f, ray->dir_x[k] = r[4], ray->dir_y[k] = r[5];          \
                ray->dir_z[k] = r[6], ray->time[k] = 0.0f, ray->tfar[k] = r[3];            \
                ray->mask[k] = ~0u, ray->id[k] = 0, ray->flags[k] = 0;                     \
                rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;                                \
            }                                                                              \
            if (any_hit) {                                                                 \
                rtc.occluded##W(valid, scene, ray, NULL);                                  \
                for (size_t k = 0; k < n; k++)                                             \
                    out[b + k] = ray->tfar[k] == -INFINITY ? 1.0f : 0.0f;                  \
            } else {                                                                       \
                rtc.intersect##W(valid, scene, &rh, NULL);                                 \
                for (size_t k = 0; k < n; k++)                                             \
                    out[b + k] = rh.hit.geomID[k] == RTC_INVALID_GEOMETRY_ID               \
                                     ? INFINITY                                            \
                                     : ray->tfar[k];                                       \
            }                                                                              \
        }                                                                                  \
    }
TRACE_PACKET(8)
TRACE_PACKET(16)

/* Rays whose result differs from the reference: hit/miss, or t by more than 1e-4
 * relative (the modes may visit triangles in different orders). */
static size_t differ(const float *a, const float *b) {
    size_t bad = 0;
    for (size_t i = 0; i < nrays; i++) {
        if (isinf(a[i]) != isinf(b[i])) bad++;
        else if (!isinf(a[i]) && fabsf(a[i] - b[i]) > 1e-4f * fmaxf(1.0f, fabsf(a[i]))) bad++;
    }
    return bad;
}

typedef void (*trace_fn)(RTCScene, float *);

static void timed(const char *name, RTCScene scene, trace_fn f, int repeats, float *out,
                  const float *reference, int last) {
    f(scene, out); /* warm-up */
    printf("    \"%s\": {\"seconds\": [", name);
    for (int r = 0; r < repeats; r++) {
        double t0 = now();
        f(scene, out);
        printf("%s%.9f", r ? ", " : "", now() - t0);
    }
    printf("]");
    if (reference) printf(", \"differ\": %zu", differ(reference, out));
    printf("}%s\n", last ? "" : ",");
}

int main(int argc, char **argv) {
    if (argc != 9)
        die("usage: embree_rays LIBEMBREE4 TRIANGLES RAYS closest|any REPEATS "
            "BUILD_THREADS BUILD_REPEATS OUT",
            NULL);
    load_api(argv[1]);
    tris = read_floats(argv[2], 9, &ntris);
    rays = read_floats(argv[3], 8, &nrays);
    if (strcmp(argv[4], "closest") && strcmp(argv[4], "any")) die("query is not closest|any", argv[4]);
    any_hit = !strcmp(argv[4], "any");
    int repeats = atoi(argv[5]), build_threads = atoi(argv[6]), build_repeats = atoi(argv[7]);
    if (repeats < 1) die("REPEATS must be at least 1", argv[5]);
    if (build_repeats < 0) die("BUILD_REPEATS must not be negative", argv[7]);

    char config[64];
    snprintf(config, sizeof config, "threads=%d", build_threads > 0 ? build_threads : 0);
    device = rtc.newDevice(build_threads > 0 ? config : NULL);
    if (!device) die("rtcNewDevice failed", NULL);
    long major = (long)rtc.getDeviceProperty(device, RTC_DEVICE_PROPERTY_VERSION_MAJOR);
    long version = (long)rtc.getDeviceProperty(device, RTC_DEVICE_PROPERTY_VERSION);
    if (major != 4) die("not Embree 4 (these declarations are Embree 4's)", argv[1]);

    printf("{\n  \"embree_version\": %ld,\n  \"rays\": %zu,\n  \"triangles\": %zu,\n", version,
           nrays, ntris);
    printf("  \"build_seconds\": [");
    for (int r = 0; build_repeats > 0 && r <= build_repeats; r++) { /* 0: a warm-up */
        double t0 = now();
        RTCScene s = build(RTC_SCENE_FLAG_NONE);
        double dt = now() - t0;
        rtc.releaseScene(s);
        if (r) printf("%s%.9f", r > 1 ? ", " : "", dt);
    }
    printf("],\n  \"modes\": {\n");
    RTCScene scene = build(RTC_SCENE_FLAG_NONE), robust = build(RTC_SCENE_FLAG_ROBUST);
    float *ref = malloc(4 * nrays), *out = malloc(4 * nrays);
    if (!ref || !out) die("out of memory", NULL);
    timed("default", scene, trace_single, repeats, ref, NULL, 0);
    timed("robust", robust, trace_single, repeats, out, ref, 0);
    timed("packet8", scene, trace_packet8, repeats, out, ref, 0);
    timed("packet16", scene, trace_packet16, repeats, out, ref, 1);
    printf("  }\n}\n");

    FILE *f = fopen(argv[8], "wb");
    if (!f || fwrite(ref, 4, nrays, f) != nrays || fclose(f)) die("cannot write", argv[8]);
    return 0;
}

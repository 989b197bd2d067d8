// Embree 3 wrapper: one device (given the render's thread count), one scene with one
// triangle geometry holding every triangle of the Scene in its order (primID = triangle).
#include "scene/accel.h"

#include <embree3/rtcore.h>

#include <cstring>
#include <mutex>
#include <string>

#include "core/error.h"
#include "core/sampling.h"

namespace rs {

struct RayAccel::Impl {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    std::mutex errorMutex;
    std::string firstError;
    std::once_flag bvhOnce;
    std::unique_ptr<TriangleBvh> bvh;

    ~Impl() {
        if (scene) rtcReleaseScene(scene);
        if (device) rtcReleaseDevice(device);
    }
    void throwIfError(const char* what) {
        std::lock_guard<std::mutex> lock(errorMutex);
        if (!firstError.empty()) throw Error(ErrorKind::Embree, std::string("embree: ") + what + ": " + firstError);
    }
};

static void onEmbreeError(void* user, RTCError code, const char* message) {
    auto* impl = static_cast<RayAccel::Impl*>(user);
    std::lock_guard<std::mutex> lock(impl->errorMutex);
    if (impl->firstError.empty())
        impl->firstError = std::string(message ? message : "error") + " (code " + std::to_string(int(code)) + ")";
}

// Cut-out surfaces (alphaMode MASK or BLEND): every query, single rays and packets, closest
// hit and occlusion, skips the hits where the surface is not there. BLEND's random number is
// a hash of the ray and the triangle: the same ray always makes the same choice.
static void alphaFilter(const RTCFilterFunctionNArguments* args) {
    const auto* scene = static_cast<const Scene*>(args->geometryUserPtr);
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] == 0) continue;
        const uint32_t tri = RTCHitN_primID(args->hit, args->N, i);
        const float b1 = RTCHitN_u(args->hit, args->N, i), b2 = RTCHitN_v(args->hit, args->N, i);
        float u = 0.f;
        if (scene->materials[scene->triMaterial[tri]].alphaMode == AlphaMode::Blend) {
            uint64_t h = tri;
            for (float f : {RTCRayN_org_x(args->ray, args->N, i), RTCRayN_org_y(args->ray, args->N, i),
                            RTCRayN_org_z(args->ray, args->N, i), RTCRayN_dir_x(args->ray, args->N, i),
                            RTCRayN_dir_y(args->ray, args->N, i), RTCRayN_dir_z(args->ray, args->N, i)}) {
                uint32_t bits;
                std::memcpy(&bits, &f, sizeof bits);
                h = mix64(h ^ bits);
            }
            u = toUnitFloat(uint32_t(h >> 32));
        }
        if (!scene->solidAt(tri, b1, b2, u)) args->valid[i] = 0;
    }
}

RayAccel::RayAccel(const Scene& scene, int threads) : impl_(std::make_unique<Impl>()), scene_(scene) {
    std::string cfg = "threads=" + std::to_string(std::max(threads, 1)) + ",user_threads=0";
    impl_->device = rtcNewDevice(cfg.c_str());
    if (!impl_->device)
        throw Error(ErrorKind::Embree, "embree: cannot create a device (error " + std::to_string(int(rtcGetDeviceError(nullptr))) + ")");
    rtcSetDeviceErrorFunction(impl_->device, onEmbreeError, impl_.get());

    impl_->scene = rtcNewScene(impl_->device);
    rtcSetSceneFlags(impl_->scene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(impl_->scene, RTC_BUILD_QUALITY_HIGH);
    RTCGeometry geom = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    size_t n = scene.triangleCount();
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                          3 * sizeof(float), 3 * n));
    auto* idx = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                               3 * sizeof(uint32_t), n));
    impl_->throwIfError("allocating the vertex buffer");
    for (size_t i = 0; i < 3 * n; ++i) {
        v[3 * i] = scene.positions[i].x;
        v[3 * i + 1] = scene.positions[i].y;
        v[3 * i + 2] = scene.positions[i].z;
        idx[i] = uint32_t(i);
    }
    if (scene.hasCutouts()) {
        rtcSetGeometryUserData(geom, const_cast<Scene*>(&scene));
        rtcSetGeometryIntersectFilterFunction(geom, alphaFilter);
        rtcSetGeometryOccludedFilterFunction(geom, alphaFilter);
    }
    rtcCommitGeometry(geom);
    rtcAttachGeometry(impl_->scene, geom);
    rtcReleaseGeometry(geom);
    rtcCommitScene(impl_->scene);
    impl_->throwIfError("building the BVH");
}

RayAccel::~RayAccel() = default;

const TriangleBvh& RayAccel::triangleBvh() const {
    std::call_once(impl_->bvhOnce, [&] { impl_->bvh = std::make_unique<TriangleBvh>(scene_); });
    return *impl_->bvh;
}

bool RayAccel::intersect(const Vec3& o, const Vec3& d, float tmax, SurfacePoint& hit, float& t) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh;
    rh.ray.org_x = o.x; rh.ray.org_y = o.y; rh.ray.org_z = o.z;
    rh.ray.dir_x = d.x; rh.ray.dir_y = d.y; rh.ray.dir_z = d.z;
    rh.ray.tnear = 0.f;
    rh.ray.tfar = tmax;
    rh.ray.mask = 0xffffffffu;
    rh.ray.flags = 0;
    rh.ray.time = 0.f;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(impl_->scene, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;

    t = rh.ray.tfar;
    uint32_t tri = rh.hit.primID;
    float b1 = rh.hit.u, b2 = rh.hit.v;
    const Scene& s = scene_;
    hit.tri = tri;
    hit.material = s.triMaterial[tri];
    hit.p = o + t * d;
    hit.ng = s.geometricNormal(tri);
    hit.attr = s.attributesAt(tri, b1, b2);
    hit.ns = s.shadingNormalAt(tri, b1, b2, hit.attr);
    hit.frontFace = glm::dot(d, hit.ng) < 0.f;
    return true;
}

bool RayAccel::occluded(const Vec3& o, const Vec3& d, float tmax) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRay ray;
    ray.org_x = o.x; ray.org_y = o.y; ray.org_z = o.z;
    ray.dir_x = d.x; ray.dir_y = d.y; ray.dir_z = d.z;
    ray.tnear = 0.f;
    ray.tfar = tmax;
    ray.mask = 0xffffffffu;
    ray.flags = 0;
    ray.time = 0.f;
    rtcOccluded1(impl_->scene, &ctx, &ray);
    return ray.tfar < 0.f;
}

// Lane i of a packet: o + t·d for t in (0, tfar).
static void setLane(RTCRay16& r, int i, const Vec3& o, const Vec3& d, float tfar) {
    r.org_x[i] = o.x, r.org_y[i] = o.y, r.org_z[i] = o.z;
    r.dir_x[i] = d.x, r.dir_y[i] = d.y, r.dir_z[i] = d.z;
    r.tnear[i] = 0.f, r.tfar[i] = tfar, r.time[i] = 0.f;
    r.mask[i] = 0xffffffffu, r.id[i] = uint32_t(i), r.flags[i] = 0;
}

uint32_t RayAccel::occludedToPoint(const Vec3* from, int count, const Vec3& to) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    RTCRay16 rays;
    alignas(64) int valid[kPacket];
    for (int i = 0; i < kPacket; ++i) {
        const bool live = i < count;
        valid[i] = live ? -1 : 0;
        const Vec3 o = live ? from[i] : to;
        setLane(rays, i, o, to - o, 1.f);
    }
    rtcOccluded16(valid, impl_->scene, &ctx, &rays);
    uint32_t hidden = 0;
    for (int i = 0; i < count; ++i)
        if (rays.tfar[i] < 0.f) hidden |= 1u << i;
    return hidden;
}

uint32_t RayAccel::intersectParallel(const Vec3* from, int count, const Vec3& dir, const float* tmax, float* t,
                                     uint32_t* tri) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    RTCRayHit16 rh;
    alignas(64) int valid[kPacket];
    for (int i = 0; i < kPacket; ++i) {
        const bool live = i < count;
        valid[i] = live ? -1 : 0;
        setLane(rh.ray, i, live ? from[i] : from[0], dir, live ? tmax[i] : 0.f);
        rh.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID, rh.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
    }
    rtcIntersect16(valid, impl_->scene, &ctx, &rh);
    uint32_t hits = 0;
    for (int i = 0; i < count; ++i) {
        if (rh.hit.geomID[i] == RTC_INVALID_GEOMETRY_ID) continue;
        hits |= 1u << i;
        t[i] = rh.ray.tfar[i];
        tri[i] = rh.hit.primID[i];
    }
    return hits;
}

}  // namespace rs

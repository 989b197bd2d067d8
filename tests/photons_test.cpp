// The photon tracer: energy bookkeeping in a closed room, quotas, determinism, radii, and the
// stratification of its quasi-random sequence.
#include <gtest/gtest.h>

#include <cstring>

#include "scene/accel.h"
#include "scene/lights.h"
#include "core/log.h"
#include "core/parallel.h"
#include "splat/photons.h"
#include "core/qmc.h"
#include "test_scenes.h"

using namespace rs;
using namespace rs::test;

namespace {

// A closed 2 m room of albedo ρ, looking inwards, with a 0.5×0.5 m light just below the
// ceiling facing down; optionally a glass ball on the floor.
Scene closedRoom(float rho, bool glassBall) {
    Scene s;
    uint32_t wall = addMaterial(s, MaterialKind::Lambert, Vec3(rho));
    uint32_t light = addMaterial(s, MaterialKind::Lambert, Vec3(0.f), Vec3(10.f));
    addBox(s, {-1, 0, -1}, {1, 2, 1}, wall, /*inward=*/true);
    addQuad(s, {-0.25f, 1.9f, -0.25f}, {0.25f, 1.9f, -0.25f}, {0.25f, 1.9f, 0.25f}, {-0.25f, 1.9f, 0.25f}, light);
    if (glassBall) addSphere(s, {0.f, 0.4f, 0.f}, 0.4f, 3, addMaterial(s, MaterialKind::Glass, Vec3(1.f)));
    s.computeBounds();
    return s;
}

}  // namespace

TEST(ScrambledHalton, FirstPointsAreStratifiedPerDimension) {
    ScrambledHalton h(42, 8);
    for (auto [dim, base, count] : {std::tuple{0, 2, 1024}, std::tuple{1, 3, 729}, std::tuple{2, 5, 625}}) {
        std::vector<int> hits(count, 0);
        for (int i = 0; i < count; ++i) {
            float x = h.sample(uint64_t(i), dim);
            ASSERT_GE(x, 0.f);
            ASSERT_LT(x, 1.f);
            hits[std::min(count - 1, int(x * count))]++;
        }
        for (int c : hits) EXPECT_EQ(c, 1) << "base " << base;
    }
    ScrambledHalton other(43, 8);
    EXPECT_NE(h.sample(5, 0), other.sample(5, 0));  // the seed scrambles
}

// Every path's first segment ends on a wall: the direct photons carry exactly the emitted
// power; the indirect ones carry Φ·ρ/(1−ρ) (every later bounce, summed) up to noise.
TEST(PhotonTracer, ClosedRoomConservesEnergy) {
    const float rho = 0.5f;
    Scene s = closedRoom(rho, false);
    RayAccel accel(s, 1);
    LightSampler lights(s);
    ThreadPool pool(2);
    PhotonSettings st;
    st.photons = 40000;
    st.maxDepth = 64;
    PhotonMap map = tracePhotons(s, accel, lights, st, pool, silentReporter());
    DVec3 sum[kPhotonClassCount] = {};
    for (const PhotonRay& r : map.rays) sum[r.cls] += DVec3(r.flux);
    double power = luminance(s.emittedPower());
    EXPECT_NEAR(sum[kPhotonDirect].x / power, 1.0, 1e-4);
    EXPECT_NEAR(sum[kPhotonIndirect].x / power, rho / (1 - rho), 0.03);
    // No glass: no caustics, and their quota went to the other classes.
    EXPECT_EQ(map.count[kPhotonCaustic], 0);
    EXPECT_EQ(map.count[kPhotonDirect] + map.count[kPhotonIndirect], st.photons);
}

TEST(PhotonTracer, GlassBallMakesCausticsAndQuotasHold) {
    Scene s = closedRoom(0.5f, true);
    RayAccel accel(s, 1);
    LightSampler lights(s);
    ThreadPool pool(2);
    PhotonSettings st;
    st.photons = 20000;
    PhotonMap map = tracePhotons(s, accel, lights, st, pool, silentReporter());
    EXPECT_EQ(map.count[kPhotonDirect], 4000);
    EXPECT_EQ(map.count[kPhotonIndirect], 10000);
    EXPECT_EQ(map.count[kPhotonCaustic], 6000);
    // Caustics are rarer: more paths were needed to fill them.
    EXPECT_GT(map.pathsFor[kPhotonCaustic], map.pathsFor[kPhotonDirect]);
    for (const PhotonRay& r : map.rays) {
        int c = r.cls;
        EXPECT_GE(r.radius, st.minRadius[c] * st.voxelSize * 0.9999f);
        EXPECT_LE(r.radius, st.maxRadius[c] * st.voxelSize * 1.0001f);
        EXPECT_NEAR(glm::length(r.dir), 1.f, 1e-5f);
        EXPECT_GT(r.length, 0.f);
    }
    // Caustic photons under the ball: they end on the floor beneath it.
    int under = 0;
    for (const PhotonRay& r : map.rays) {
        Vec3 end = r.origin + r.length * r.dir;
        if (r.cls == kPhotonCaustic && end.y < 1e-3f && std::hypot(end.x, end.z) < 0.5f) ++under;
    }
    EXPECT_GT(under, map.count[kPhotonCaustic] / 2);
}

TEST(PhotonTracer, ThreadCountDoesNotChangePhotons) {
    Scene s = closedRoom(0.6f, true);
    RayAccel accel(s, 2);
    LightSampler lights(s);
    PhotonSettings st;
    st.photons = 10000;
    ThreadPool one(1), two(2);
    PhotonMap a = tracePhotons(s, accel, lights, st, one, silentReporter());
    PhotonMap b = tracePhotons(s, accel, lights, st, two, silentReporter());
    ASSERT_EQ(a.rays.size(), b.rays.size());
    EXPECT_EQ(0, std::memcmp(a.rays.data(), b.rays.data(), a.rays.size() * sizeof(PhotonRay)));
}

// animation_test: glTF animations evaluated against hand-computed values for each interpolation,
// parent chains posed through the loader and through the walkthrough's camera alike, frame
// numbering in output names, a frame rendered alone and within a range giving the same image, a
// file flattened again at each pose, and a swinging door's shadow moving where geometry says.
#include <array>
#include <fstream>

#include "scene/animation.h"
#include "scene/camera.h"
#include "test_scenes.h"
#include "walkthrough.h"

namespace rs {
namespace {

using test::TempDir;

constexpr float kTol = 1e-6f;

AnimationChannel channel(AnimatedPath path, Interpolation interpolation, std::vector<float> times, std::vector<Vec4> values) {
    AnimationChannel c;
    c.node = 0;
    c.path = path;
    c.interpolation = interpolation;
    c.times = std::move(times);
    c.values = std::move(values);
    return c;
}

void expectNear(const Vec4& a, const Vec4& b, float tol = kTol) {
    for (int k = 0; k < 4; ++k) EXPECT_NEAR(a[k], b[k], tol) << "component " << k;
}

TEST(Animation, StepHoldsEachKeyUntilTheNextAndTheEndsOutside) {
    const Vec4 a(1, 2, 3, 0), b(4, 5, 6, 0), c(7, 8, 9, 0);
    const AnimationChannel s = channel(AnimatedPath::Translation, Interpolation::Step, {1.f, 2.f, 4.f}, {a, b, c});
    expectNear(s.at(0.f), a);    // before the first key: held
    expectNear(s.at(1.f), a);
    expectNear(s.at(1.99f), a);
    expectNear(s.at(2.f), b);    // a key's value from its own time on
    expectNear(s.at(3.9f), b);
    expectNear(s.at(4.f), c);
    expectNear(s.at(100.f), c);  // after the last: held
}

TEST(Animation, LinearTranslationAndScaleMixByTheKeyInterval) {
    const AnimationChannel s = channel(AnimatedPath::Scale, Interpolation::Linear, {0.f, 2.f, 3.f},
                                       {Vec4(1, 1, 1, 0), Vec4(3, 1, -1, 0), Vec4(3, 2, -1, 0)});
    expectNear(s.at(0.5f), Vec4(1.5f, 1.f, 0.5f, 0.f));  // a quarter of the first interval
    expectNear(s.at(2.5f), Vec4(3.f, 1.5f, -1.f, 0.f));  // half of the second
}

TEST(Animation, LinearRotationSlerpsAlongTheShorterArc) {
    // Identity to 90 degrees about +Y, the second key written as its negative (the same rotation):
    // halfway is 45 degrees about +Y, not the long way round.
    const float h = std::sqrt(0.5f);
    const AnimationChannel r = channel(AnimatedPath::Rotation, Interpolation::Linear, {0.f, 1.f},
                                       {Vec4(0, 0, 0, 1), Vec4(0, -h, 0, -h)});
    const Vec4 q = r.at(0.5f);
    const float s = std::sin(kPi / 8.f), c = std::cos(kPi / 8.f);
    const float sign = q.w < 0.f ? -1.f : 1.f;
    expectNear(sign * q, Vec4(0, s, 0, c));
    // A third of the way: 30 degrees (slerp, not a normalized lerp, which gives about 27.4).
    const Vec4 third = r.at(1.f / 3.f);
    EXPECT_NEAR(2.f * std::acos(std::abs(third.w)), kPi / 6.f, 1e-5f);
}

TEST(Animation, CubicSplineIsTheHermiteSplineWithTangentsScaledByTheInterval) {
    // Keys at t = 0 and 2 (interval 2): values 0 and 1, out-tangent 3 at the first, in-tangent -1
    // at the second (in x). p(s) = h00 p0 + 2 h10 m0 + h01 p1 + 2 h11 m1 with s = t / 2.
    const Vec4 zero(0.f);
    const AnimationChannel c = channel(AnimatedPath::Translation, Interpolation::CubicSpline, {0.f, 2.f},
                                       {Vec4(9, 0, 0, 0), zero, Vec4(3, 0, 0, 0), Vec4(-1, 0, 0, 0), Vec4(1, 0, 0, 0), Vec4(9, 0, 0, 0)});
    // s = 0.5: 0 + 2·0.125·3 + 0.5·1 + 2·(−0.125)·(−1) = 1.5
    EXPECT_NEAR(c.at(1.f).x, 1.5f, kTol);
    // s = 0.25: 2·0.140625·3 + 0.15625·1 + 2·(−0.046875)·(−1) = 1.09375
    EXPECT_NEAR(c.at(0.5f).x, 1.09375f, kTol);
    // The keys' values at the keys and outside, the tangents (9) never.
    EXPECT_NEAR(c.at(0.f).x, 0.f, kTol);
    EXPECT_NEAR(c.at(2.f).x, 1.f, kTol);
    EXPECT_NEAR(c.at(-1.f).x, 0.f, kTol);
    EXPECT_NEAR(c.at(5.f).x, 1.f, kTol);
}

TEST(Animation, CubicSplineRotationsComeOutNormalized) {
    const float h = std::sqrt(0.5f);
    const AnimationChannel c = channel(AnimatedPath::Rotation, Interpolation::CubicSpline, {0.f, 1.f},
                                       {Vec4(0.f), Vec4(0, 0, 0, 1), Vec4(0.f), Vec4(0.f), Vec4(0, h, 0, h), Vec4(0.f)});
    const Vec4 q = c.at(0.5f);
    EXPECT_NEAR(glm::length(q), 1.f, kTol);
    // Zero tangents and symmetric weights: halfway between the two, normalized: 45 degrees about +Y.
    expectNear(q, Vec4(0, std::sin(kPi / 8.f), 0, std::cos(kPi / 8.f)), 1e-6f);
}

// -- Through the loader: a glTF file written here ----------------------------------------------

std::string join(const std::vector<std::string>& parts) {
    std::string s;
    for (size_t i = 0; i < parts.size(); ++i) s += (i ? "," : "") + parts[i];
    return s;
}

std::string floats(const std::vector<float>& v) { return std::string(reinterpret_cast<const char*>(v.data()), v.size() * 4); }

// A glTF buffer of float accessors, written beside the file that names it.
struct FloatBuffer {
    std::string bin;
    std::vector<std::string> views, accessors;
    // An accessor of `count` elements of `type` over `bytes`; its index as text.
    std::string add(const std::string& bytes, int count, const char* type) {
        views.push_back("{\"buffer\":0,\"byteOffset\":" + std::to_string(bin.size()) + ",\"byteLength\":" + std::to_string(bytes.size()) + "}");
        bin += bytes;
        accessors.push_back("{\"bufferView\":" + std::to_string(views.size() - 1) + ",\"componentType\":5126,\"count\":" +
                            std::to_string(count) + ",\"type\":\"" + type + "\"}");
        return std::to_string(accessors.size() - 1);
    }
    // The document's accessors, views and buffer members, the buffer in file `bin` of `dir`.
    std::string json(const TempDir& dir, const std::string& binName) const {
        std::ofstream(dir.file(binName), std::ios::binary) << bin;
        return "\"accessors\":[" + join(accessors) + "],\"bufferViews\":[" + join(views) + "],"
               "\"buffers\":[{\"byteLength\":" + std::to_string(bin.size()) + ",\"uri\":\"" + binName + "\"}]";
    }
};

// A rig (animated: translation (0,0,0) → (2,0,0) and rotation 0 → 90 degrees about +Y over one
// second, LINEAR) with two children 1 m along its +Z: a camera, and (with `meshChild`) a triangle.
std::string writeRigScene(const TempDir& dir, bool meshChild) {
    FloatBuffer buffer;
    auto add = [&](const std::string& bytes, int count, const char* type) { return buffer.add(bytes, count, type); };
    const float h = std::sqrt(0.5f);
    const std::string tri = add(floats({0, 0, 0, 1, 0, 0, 0, 1, 0}), 3, "VEC3");
    const std::string times = add(floats({0.f, 1.f}), 2, "SCALAR");
    const std::string moves = add(floats({0, 0, 0, 2, 0, 0}), 2, "VEC3");
    const std::string turns = add(floats({0, 0, 0, 1, 0, h, 0, h}), 2, "VEC4");
    // A ground triangle far below, so that a cameras-only scene still has geometry.
    const std::string ground = add(floats({-50, -5, -50, 50, -5, -50, 0, -5, 50}), 3, "VEC3");
    std::string nodes = "{\"name\":\"rig\",\"children\":[1" + std::string(meshChild ? ",2" : "") + "]},"
                        "{\"name\":\"cam\",\"camera\":0,\"translation\":[0,0,1]},"
                        "{\"name\":\"thing\",\"mesh\":0,\"translation\":[0,0,1]},"
                        "{\"name\":\"ground\",\"mesh\":1}";
    std::string doc = "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0,3]}],\"nodes\":[" + nodes + "],"
                      "\"cameras\":[{\"type\":\"perspective\",\"perspective\":{\"yfov\":0.8,\"znear\":0.1}}],"
                      "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":" + tri + "}}]},"
                      "{\"primitives\":[{\"attributes\":{\"POSITION\":" + ground + "}}]}],"
                      "\"animations\":[{\"name\":\"walk\",\"samplers\":[{\"input\":" + times + ",\"output\":" + moves + "},"
                      "{\"input\":" + times + ",\"output\":" + turns + "}],\"channels\":["
                      "{\"sampler\":0,\"target\":{\"node\":0,\"path\":\"translation\"}},"
                      "{\"sampler\":1,\"target\":{\"node\":0,\"path\":\"rotation\"}}]}],"
                      + buffer.json(dir, "rig.bin") + "}";
    std::ofstream(dir.file("rig.gltf"), std::ios::binary) << doc;
    return dir.file("rig.gltf");
}

TEST(Animation, ParentChainPosesChildrenAsHandComputed) {
    TempDir dir;
    const std::string path = writeRigScene(dir, true);
    const Scene rest = loadScene(path, silentReporter());
    const SceneAnimation& a = rest.animation;
    ASSERT_EQ(a.animations.size(), 1u);
    EXPECT_FALSE(a.movesOnlyCameras({0}));  // the triangle rides on the rig
    const std::vector<Mat4> pose = a.pose({0}, 0.5f);
    const Scene posed = loadScene(path, silentReporter(), 0, &pose);
    // At t = 0.5 the rig stands at (1,0,0) turned 45 degrees about +Y: a point 1 m along its +Z is
    // at (1 + sin 45, 0, cos 45), and the camera looks along the turned −Z, (−sin 45, 0, −cos 45).
    const float s = std::sqrt(0.5f);
    ASSERT_EQ(posed.cameras.size(), 1u);
    const Camera& cam = posed.cameras[0];
    EXPECT_NEAR(cam.position.x, 1.f + s, 1e-5f);
    EXPECT_NEAR(cam.position.y, 0.f, 1e-5f);
    EXPECT_NEAR(cam.position.z, s, 1e-5f);
    EXPECT_NEAR(cam.forward.x, -s, 1e-5f);
    EXPECT_NEAR(cam.forward.z, -s, 1e-5f);
    // The triangle's vertices at the rig's local (0,0,1) and (1,0,1), turned (x' = x cos + z sin,
    // z' = −x sin + z cos) and moved: (1 + s, 0, s) and (1 + 2s, 0, 0).
    EXPECT_NEAR(posed.positions[0].x, 1.f + s, 1e-5f);
    EXPECT_NEAR(posed.positions[0].z, s, 1e-5f);
    EXPECT_NEAR(posed.positions[1].x, 1.f + 2.f * s, 1e-5f);
    EXPECT_NEAR(posed.positions[1].z, 0.f, 1e-5f);
    // The still: the file's own transforms (rig at the origin, unturned).
    EXPECT_NEAR(rest.cameras[0].position.z, 1.f, 1e-6f);
    EXPECT_NEAR(rest.positions[0].x, 0.f, 1e-6f);
}

TEST(Animation, WalkthroughCameraEqualsTheLoadersPosedCameraBitForBit) {
    // Where only cameras move the walkthrough poses the camera itself; it must be the camera the
    // loader flattens from the same pose.
    TempDir dir;
    const std::string path = writeRigScene(dir, false);
    const Scene rest = loadScene(path, silentReporter());
    const SceneAnimation& a = rest.animation;
    EXPECT_TRUE(a.movesOnlyCameras({0}));
    for (float t : {0.f, 0.3f, 0.77f, 2.f}) {
        const std::vector<Mat4> pose = a.pose({0}, t);
        const Scene posed = loadScene(path, silentReporter(), 0, &pose);
        const Camera placed = placeCamera(rest.cameras[0], a.worldFrom(a.cameraNode[0], pose));
        const Camera& loaded = posed.cameras[0];
        for (int k = 0; k < 3; ++k) {
            EXPECT_EQ(placed.position[k], loaded.position[k]) << "t " << t;
            EXPECT_EQ(placed.forward[k], loaded.forward[k]) << "t " << t;
            EXPECT_EQ(placed.right[k], loaded.right[k]) << "t " << t;
            EXPECT_EQ(placed.up[k], loaded.up[k]) << "t " << t;
        }
    }
    // With no pose the loader's nodes are the rest pose's: pose() reproduces the file.
    const std::vector<Mat4> restPose = a.pose({}, 0.f);
    const Scene again = loadScene(path, silentReporter(), 0, &restPose);
    EXPECT_EQ(again.positions, rest.positions);
    EXPECT_EQ(again.cameras[0].position, rest.cameras[0].position);
}

TEST(Animation, SceneFilePosedIsTheLoadersPosedSceneBitForBit) {
    // A walkthrough whose mesh moves reads the file once and flattens it at each frame's pose:
    // each must be the scene loadScene flattens from the file at that pose, whatever was posed
    // before, and the rest pose again the still's scene.
    TempDir dir;
    const std::string path = writeRigScene(dir, true);
    const Scene rest = loadScene(path, silentReporter());
    SceneFile file(path, silentReporter());
    auto expectSame = [](const Scene& a, const Scene& b, const std::string& what) {
        EXPECT_EQ(a.positions, b.positions) << what;
        EXPECT_EQ(a.normals, b.normals) << what;
        EXPECT_EQ(a.uvs, b.uvs) << what;
        EXPECT_EQ(a.triMaterial, b.triMaterial) << what;
        EXPECT_EQ(a.objectNames, b.objectNames) << what;
        EXPECT_EQ(a.materials.size(), b.materials.size()) << what;
        EXPECT_EQ(a.bounds.lo, b.bounds.lo) << what;
        EXPECT_EQ(a.bounds.hi, b.bounds.hi) << what;
        ASSERT_EQ(a.cameras.size(), b.cameras.size()) << what;
        for (size_t i = 0; i < a.cameras.size(); ++i) {
            EXPECT_EQ(a.cameras[i].position, b.cameras[i].position) << what;
            EXPECT_EQ(a.cameras[i].forward, b.cameras[i].forward) << what;
        }
        EXPECT_EQ(a.animation.cameraNode, b.animation.cameraNode) << what;
    };
    expectSame(file.scene(), rest, "as read");
    const SceneAnimation& a = rest.animation;
    for (float t : {0.5f, 0.2f, 0.5f}) {
        const std::vector<Mat4> pose = a.pose({0}, t);
        const Scene loaded = loadScene(path, silentReporter(), 0, &pose);
        expectSame(file.pose(pose), loaded, "t " + std::to_string(t));
        EXPECT_NE(loaded.positions, rest.positions) << "the rig moved the triangle at t " << t;
    }
    const std::vector<Mat4> restPose = a.pose({}, 0.f);
    expectSame(file.pose(restPose), rest, "back at rest");
}

// A small, quick walkthrough of the rig scene under a uniform sky.
RenderConfig walkConfig(const std::string& scene, const TempDir& dir, int first, int last) {
    RenderConfig cfg;
    cfg.scene = scene;
    cfg.output = dir.file("frame.exr");
    cfg.width = cfg.height = 24;
    cfg.spp = 1;
    cfg.directSpp = 2;
    cfg.grid = 32;
    cfg.voxelizer = "cpu";
    cfg.passes = 1;
    cfg.photons = 5000;
    cfg.sky = Vec3(1.f);
    cfg.firstFrame = first;
    cfg.lastFrame = last;
    return cfg;
}

bool sameFilm(const Film& a, const Film& b) {
    for (int b2 = 0; b2 < FixedFilm::kBuffers; ++b2)
        if (a.buffer(b2) != b.buffer(b2)) return false;
    return a.width == b.width && a.height == b.height;
}

TEST(Walkthrough, EachFrameIsTheStillOfItsPosedScene) {
    // Whether only the camera moves (the scene loaded once, the BVH, the occlusion grid and the
    // photons kept) or a mesh rides on the rig (each frame loaded as posed), frame f is bit for
    // bit the still of the file posed at f / fps; the frames differ from each other. The paper's
    // visibility (the grid's mask) too, where the grid is built for the first frame alone.
    for (const auto& [meshChild, mask] : {std::pair{false, false}, std::pair{true, false}, std::pair{false, true}}) {
        TempDir dir;
        const std::string path = writeRigScene(dir, meshChild);
        RenderConfig cfg = walkConfig(path, dir, 6, 12);
        if (mask) cfg.visibility = Visibility::Mask;
        Walkthrough walk(cfg, silentReporter(), singleProcess());
        EXPECT_EQ(walk.movesOnlyCameras(), !meshChild);
        RenderConfig still = cfg;
        still.firstFrame = still.lastFrame = -1;
        std::vector<Film> frames;
        for (int frame : {6, 12}) {
            RenderResult r = walk.renderFrame(frame);
            const std::vector<Mat4> pose = walk.scene().animation.pose({0}, float(frame) / cfg.fps);
            const Scene posed = loadScene(path, silentReporter(), 0, &pose);
            const RenderResult expected = render(posed, still, silentReporter());
            EXPECT_TRUE(sameFilm(r.film, expected.film)) << "frame " << frame << (meshChild ? ", mesh moving" : ", camera only");
            // The file is read once for the range; the setup and the photons are kept across
            // frames only where only the camera moves: the one pass's photons traced for frame 6
            // alone there, and for each frame where the mesh moves.
            EXPECT_EQ(r.stats.count("scene_reads"), frame == 6 ? 1.0 : 0.0);
            EXPECT_EQ(r.stats.count("bvh_reused"), meshChild || frame == 6 ? 0.0 : 1.0);
            EXPECT_EQ(r.stats.count("photon_passes_traced"), meshChild || frame == 6 ? 1.0 : 0.0);
            EXPECT_EQ(r.stats.count("grid_reused"), meshChild || frame == 6 ? 0.0 : 1.0);
            if (mask) {
                EXPECT_EQ(r.stats.time("voxelize") > 0.0, frame == 6) << "the grid built for frame 6 alone";
            }
            frames.push_back(std::move(r.film));
        }
        EXPECT_FALSE(sameFilm(frames[0], frames[1]));
        EXPECT_GT(test::layerMean(frames[0], kDirect) + test::layerMean(frames[0], kEmission), 0.0);
    }
}

// -- A door's shadow ----------------------------------------------------------------------------

// A floor (6 m square at y = 0, grey), a point light 3 m above its centre, a black door (1 m wide,
// from 0.2 to 2 m high) hinged at (0.5, 0, 0.6) that swings kDoorOpen about +Y from frame 0 to
// frame 1 (LINEAR), and an orthographic camera 5 m up looking straight down (5 m square view).
constexpr float kDoorOpen = 70.f * kPi / 180.f;
const Vec3 kHinge(0.5f, 0.f, 0.6f), kLamp(0.f, 3.f, 0.f);
const Vec3 kDoor[4] = {{0.f, 0.2f, 0.f}, {1.f, 0.2f, 0.f}, {1.f, 2.f, 0.f}, {0.f, 2.f, 0.f}};  // about the hinge

std::string writeDoorScene(const TempDir& dir) {
    FloatBuffer buffer;
    auto add = [&](const std::string& bytes, int count, const char* type) { return buffer.add(bytes, count, type); };
    const std::string floor = add(floats({-3, 0, -3, -3, 0, 3, 3, 0, 3, -3, 0, -3, 3, 0, 3, 3, 0, -3}), 6, "VEC3");
    std::vector<float> door;
    for (int k : {0, 1, 2, 0, 2, 3}) door.insert(door.end(), {kDoor[k].x, kDoor[k].y, kDoor[k].z});
    const std::string doorMesh = add(floats(door), 6, "VEC3");
    const std::string times = add(floats({0.f, 1.f / 24.f}), 2, "SCALAR");
    const std::string turns = add(floats({0, 0, 0, 1, 0, std::sin(0.5f * kDoorOpen), 0, std::cos(0.5f * kDoorOpen)}), 2, "VEC4");
    const float h = std::sqrt(0.5f);
    auto lambert = [](const char* albedo) {
        return std::string("{\"pbrMetallicRoughness\":{\"baseColorFactor\":[") + albedo + "," + albedo + "," + albedo +
               ",1],\"metallicFactor\":0,\"roughnessFactor\":1},\"doubleSided\":true}";
    };
    std::string doc =
        "{\"asset\":{\"version\":\"2.0\"},\"extensionsUsed\":[\"KHR_lights_punctual\"],"
        "\"extensions\":{\"KHR_lights_punctual\":{\"lights\":[{\"type\":\"point\",\"intensity\":20}]}},"
        "\"scene\":0,\"scenes\":[{\"nodes\":[0,1,2,3]}],\"nodes\":["
        "{\"name\":\"floor\",\"mesh\":0},"
        "{\"name\":\"door\",\"mesh\":1,\"translation\":[0.5,0,0.6]},"
        "{\"name\":\"lamp\",\"translation\":[0,3,0],\"extensions\":{\"KHR_lights_punctual\":{\"light\":0}}},"
        "{\"name\":\"top\",\"camera\":0,\"translation\":[0,5,0.5],\"rotation\":[" + std::to_string(-h) + ",0,0," + std::to_string(h) + "]}],"
        "\"cameras\":[{\"type\":\"orthographic\",\"orthographic\":{\"xmag\":2.5,\"ymag\":2.5,\"znear\":0.1,\"zfar\":10}}],"
        "\"materials\":[" + lambert("0.5") + "," + lambert("0") + "],"
        "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":" + floor + "},\"material\":0}]},"
        "{\"primitives\":[{\"attributes\":{\"POSITION\":" + doorMesh + "},\"material\":1}]}],"
        "\"animations\":[{\"name\":\"swing\",\"samplers\":[{\"input\":" + times + ",\"output\":" + turns + "}],"
        "\"channels\":[{\"sampler\":0,\"target\":{\"node\":1,\"path\":\"rotation\"}}]}],"
        + buffer.json(dir, "door.bin") + "}";
    std::ofstream(dir.file("door.gltf"), std::ios::binary) << doc;
    return dir.file("door.gltf");
}

// The door's corners in the world at swing `angle`, computed here, not by the loader.
std::array<Vec3, 4> doorAt(float angle) {
    std::array<Vec3, 4> c;
    for (int k = 0; k < 4; ++k)
        c[k] = kHinge + Vec3(kDoor[k].x * std::cos(angle) + kDoor[k].z * std::sin(angle), kDoor[k].y,
                             -kDoor[k].x * std::sin(angle) + kDoor[k].z * std::cos(angle));
    return c;
}

// Whether the segment from the lamp to `p` crosses triangle (a, b, c) (Möller–Trumbore).
bool crosses(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
    const Vec3 d = p - kLamp, e1 = b - a, e2 = c - a, q = glm::cross(d, e2);
    const float det = glm::dot(e1, q);
    if (std::abs(det) < 1e-9f) return false;
    const Vec3 s = kLamp - a;
    const float u = glm::dot(s, q) / det;
    const Vec3 r = glm::cross(s, e1);
    const float v = glm::dot(d, r) / det, t = glm::dot(e2, r) / det;
    return u >= 0.f && v >= 0.f && u + v <= 1.f && t > 0.f && t < 1.f;
}

bool inShadow(const Vec3& p, const std::array<Vec3, 4>& door) {
    return crosses(p, door[0], door[1], door[2]) || crosses(p, door[0], door[2], door[3]);
}

TEST(Walkthrough, ADoorsShadowMovesWithTheDoorAndNothingElseChanges) {
    // Frames 0 (closed) and 1 (swung 70 degrees), by the path tracer and by photon splatting (its
    // photons traced again for frame 1). Each pixel's floor point is classed by segments to the
    // lamp past the door's corners as computed here: a pixel whose 5×5 points, spread a pixel and
    // a half around its centre, are all lit in one frame and all in the door's shadow in the other
    // is where the shadow moved, and must be dark (under 2 %) in that one. The door is black and a
    // plane does not light itself: the image is the lamp's light alone, so a pixel lit in both
    // frames more than 0.6 m from where either door stands has no reason to change at all, and
    // must agree within the pixel sampling's noise (1 % a pixel, 0.2 % on average).
    for (Method method : {Method::Path, Method::Splat}) {
        TempDir dir;
        RenderConfig cfg;
        cfg.scene = writeDoorScene(dir);
        cfg.output = dir.file("door.exr");
        cfg.method = method;
        cfg.width = 64;
        cfg.spp = method == Method::Path ? 64 : 4;
        cfg.passes = 1;
        cfg.photons = 20000;
        cfg.grid = 48;
        cfg.voxelizer = "cpu";
        cfg.firstFrame = 0;
        cfg.lastFrame = 1;
        Walkthrough walk(cfg, silentReporter(), singleProcess());
        ASSERT_FALSE(walk.movesOnlyCameras());
        const Film closed = walk.renderFrame(0).film, open = walk.renderFrame(1).film;
        ASSERT_EQ(closed.width, 64);
        ASSERT_EQ(closed.height, 64);
        const std::array<Vec3, 4> doors[2] = {doorAt(0.f), doorAt(kDoorOpen)};
        const CameraRays rays(walk.scene().camera(), closed.width, closed.height);
        auto floorAt = [&](Vec2 raster) {
            const Vec3 o = rays.origin(raster), d = rays.direction(raster);
            return o - d * (o.y / d.y);
        };
        auto nearDoor = [&](const Vec3& p) {  // within 0.6 m of the floor under either door
            for (const auto& door : doors)
                for (float s = 0.f; s <= 1.f; s += 0.05f) {
                    const Vec3 q = door[0] + s * (door[1] - door[0]);
                    if (glm::length(Vec2(p.x - q.x, p.z - q.z)) < 0.6f) return true;
                }
            return false;
        };
        const char* name = method == Method::Path ? "path" : "splat";
        int moved = 0, far = 0;
        double farDifference = 0.0;
        for (int y = 0; y < closed.height; ++y)
            for (int x = 0; x < closed.width; ++x) {
                int shadowed[2] = {0, 0};
                for (int i = -2; i <= 2; ++i)
                    for (int j = -2; j <= 2; ++j) {
                        const Vec3 p = floorAt(Vec2(x + 0.5f + 0.75f * i, y + 0.5f + 0.75f * j));
                        for (int f = 0; f < 2; ++f) shadowed[f] += inShadow(p, doors[f]);
                    }
                const size_t px = size_t(y) * closed.width + x;
                const float a = luminance(closed.beauty(px)), b = luminance(open.beauty(px));
                const bool lit[2] = {shadowed[0] == 0, shadowed[1] == 0}, dark[2] = {shadowed[0] == 25, shadowed[1] == 25};
                if ((lit[0] && dark[1]) || (dark[0] && lit[1])) {
                    ++moved;
                    EXPECT_LT(lit[0] ? b : a, 0.02f * (lit[0] ? a : b))
                        << name << ": pixel (" << x << ", " << y << ") did not " << (lit[0] ? "gain" : "lose") << " the shadow";
                } else if (lit[0] && lit[1] && !nearDoor(floorAt(Vec2(x + 0.5f, y + 0.5f)))) {
                    ++far;
                    const float d = std::abs(a - b) / std::max(a, b);
                    farDifference += d;
                    EXPECT_LT(d, 0.01f) << name << ": pixel (" << x << ", " << y << ") far from the door changed";
                }
            }
        EXPECT_GT(moved, 100) << name << ": the shadow hardly moved: the scene is not what the test means";
        EXPECT_GT(far, 1500) << name;
        EXPECT_LT(farDifference / std::max(far, 1), 0.002) << name << ": far pixels differ on average";
    }
}

TEST(Animation, FramePathsFollowBlendersNumbering) {
    EXPECT_EQ(framePath("walk_####.exr", 24, true), "walk_0024.exr");
    EXPECT_EQ(framePath("walk_####.exr", 24, false), "walk_0024.exr");
    EXPECT_EQ(framePath("walk_#.exr", 123, true), "walk_123.exr");     // the run is a least width
    EXPECT_EQ(framePath("a_##_b_###.png", 7, true), "a_##_b_007.png");  // the last run
    EXPECT_EQ(framePath("walk.exr", 24, true), "walk_0024.exr");
    EXPECT_EQ(framePath("walk.exr", 24, false), "walk.exr");
    EXPECT_EQ(framePath("out.d/walk", 3, true), "out.d/walk_0003");
    EXPECT_EQ(framePath("take#2/walk.exr", 3, true), "take#2/walk_0003.exr");  // not in a directory
}

}  // namespace
}  // namespace rs

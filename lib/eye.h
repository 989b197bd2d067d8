// Eye pass (DESIGN §4): camera rays traced with Embree; S stratified samples a pixel;
// directly seen emitters go to the film's emission layer; specular chains (glass, mirror)
// are followed with Fresnel-chosen branches; at the first non-specular hit an eye sample is
// stored. Eye samples are the only places where photon energy lands (DESIGN §9). With direct
// light by sampling, each eye sample also estimates its direct light there (direct.h).
#pragma once

#include <cstdint>
#include <vector>

#include "film.h"
#include "math.h"

namespace rs {

// Octahedral encoding of a unit vector in 32 bits (16 bits a coordinate): ~0.005° error.
uint32_t encodeUnit(const Vec3& n);
Vec3 decodeUnit(uint32_t e);

// Eye samples, structure of arrays. Sample i: world position, shading normal and geometric
// normal (both turned to the viewer's side), unit direction to the viewer (previous vertex),
// material and texture coordinate (to evaluate f_r), pixel index (y·width + x), and weight
// (1/S × the throughput of the specular chain that led here).
struct EyeSamples {
    std::vector<Vec3> position;
    std::vector<uint32_t> normal;    // encodeUnit
    std::vector<uint32_t> geomNormal;  // encodeUnit
    std::vector<uint32_t> toViewer;  // encodeUnit
    std::vector<uint32_t> material;
    std::vector<Vec2> uv;
    std::vector<uint32_t> pixel;
    std::vector<Vec3> weight;

    size_t size() const { return position.size(); }
    size_t bytes() const;
    void reserve(size_t n);
    void append(const EyeSamples& other);
    // Reorders every array: new sample i is old sample order[i].
    void permute(const std::vector<uint32_t>& order);
};


class RayAccel;
class LightSampler;
struct Camera;
struct Scene;
class ThreadPool;
class Reporter;

struct EyePassSettings {
    int width = 500, height = 500;
    int spp = 4;              // S: stratified camera samples a pixel (paper: 500×500×4)
    int firstSample = 0;      // this pass's samples are [firstSample, firstSample + S) of each pixel's sequence
    int maxSpecularDepth = 16;  // longest specular chain followed
    int directSamples = 0;    // > 0: direct light at every eye sample, by that many light samples
    uint64_t seed = 0;
};

struct EyePass {
    EyeSamples samples;  // in pixel order, then sample order
    // Emission layer (emitters seen through specular chains), albedo, normal, and with
    // directSamples the direct layer (light sampling at each eye sample, weighted by it).
    Film film;
};

// `lights` is needed only with settings.directSamples > 0.
EyePass traceEyePass(const Scene& scene, const RayAccel& accel, const LightSampler* lights, const Camera& camera,
                     const EyePassSettings& settings, ThreadPool& pool, Reporter& reporter);

}  // namespace rs

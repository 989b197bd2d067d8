// Lights chosen in proportion to their luminance power: emissive triangles (Le·π·A, emitting
// from the front face only), KHR_lights_punctual lights (4π·I for points, the cone integral
// for spots, E·π·r² over the scene's bounding disc for directional lights) and the
// environment (∫L dω · π·r²: what it sends through that disc from every direction). With light
// portals the directional lights and the environment count only what crosses the portals:
// E·A⊥(d), and ∫L(ω)·A⊥(−ω) dω.
#include "scene/lights.h"

#include <algorithm>

#include "core/sampling.h"

namespace rs {

LightSampler::LightSampler(const Scene& scene, const Environment* environment) : scene_(scene) {
    sceneCenter_ = scene.bounds.center();
    sceneRadius_ = std::max(0.5f * scene.bounds.diagonal(), 1e-4f);
    entryOfTriangle_.assign(scene.triangleCount(), -1);
    for (size_t t = 0; t + 2 < scene.portals.size(); t += 3) {
        const Vec3* v = &scene.portals[t];
        const Vec3 an = 0.5f * glm::cross(v[1] - v[0], v[2] - v[0]);
        if (glm::dot(an, an) > 0.f) portals_.push_back({v[0], v[1], v[2], an});
    }
    for (size_t t = 0; t < scene.triangleCount(); ++t) {
        const Material& m = scene.materials[scene.triMaterial[t]];
        if (!m.isEmissive()) continue;
        float power = luminance(scene.meanEmission(t)) * kPi * scene.triangleArea(t);
        if (!(power > 0.f)) continue;
        entryOfTriangle_[t] = int32_t(entries_.size());
        entries_.push_back({Kind::Area, uint32_t(t), power});
        buildTexelGrid(entries_.back());
    }
    for (size_t i = 0; i < scene.lights.size(); ++i) {
        const PunctualLight& l = scene.lights[i];
        float power = l.power(luminance(l.intensity), sceneRadius_);
        const float area = l.type == LightType::Directional ? portalArea(l.direction) : 0.f;
        if (area > 0.f) power = luminance(l.intensity) * area;
        if (!(power > 0.f)) continue;
        entries_.push_back({Kind::Punctual, uint32_t(i), power});
        // Photons of a point light that leave away from the scene's bounds meet nothing.
        for (int a = 0; a < 3 && l.type == LightType::Point && !scene.bounds.empty(); ++a)
            entries_.back().toward[a] = l.position[a] > scene.bounds.hi[a] ? -1 : l.position[a] < scene.bounds.lo[a] ? 1 : 0;
    }
    if (environment && !environment->black()) {
        environment_ = environment;
        environmentEntry_ = int32_t(entries_.size());
        float power = luminance(environment->integral()) * kPi * sqr(sceneRadius_);
        if (hasPortals()) {
            // ∫L(ω)·A⊥(−ω) dω, by the sampling density: stratified directions, L/pdf · A⊥.
            double sum = 0.0;
            const int n = 4096;
            for (int i = 0; i < n; ++i) {
                float pdf;
                const Vec3 w = environment->sample(sobol2D(uint32_t(i), 0x5eed), pdf);
                if (pdf > 0.f) sum += double(luminance(environment->radiance(w))) / pdf * portalArea(w);
            }
            power = float(sum / n);
        }
        entries_.push_back({Kind::Environment, 0, power});
    }
    onlyPunctual_ = std::all_of(entries_.begin(), entries_.end(), [](const Entry& e) { return e.kind == Kind::Punctual; });
    emissionPlaces_ = !std::all_of(entries_.begin(), entries_.end(), [&](const Entry& e) {
        return e.kind == Kind::Punctual && scene.lights[e.index].type != LightType::Directional;
    });
    for (const Entry& e : entries_) {
        if (e.kind != Kind::Area) continue;
        const Vec3* v = &scene.positions[3 * e.index];
        const Vec3 c = (v[0] + v[1] + v[2]) / 3.f;
        const float reach = std::sqrt(std::max({glm::dot(v[0] - c, v[0] - c), glm::dot(v[1] - c, v[1] - c), glm::dot(v[2] - c, v[2] - c)}));
        emitterSpheres_.emplace_back(c, kNearEmitter * reach);
    }
    double total = 0.0;
    for (const Entry& e : entries_) total += e.power;
    double acc = 0.0;
    for (const Entry& e : entries_) {
        acc += e.power;
        cdf_.push_back(float(acc / total));
    }
    if (!cdf_.empty()) cdf_.back() = 1.f;
}

void LightSampler::buildTexelGrid(Entry& e) {
    const uint32_t material = scene_.triMaterial[e.index];
    const TextureRef& ref = scene_.materials[material].emissiveTexture;
    if (!ref.present()) return;
    // As many cells as the triangle spans texels, up to kMaxGridSide².
    const Texture& tex = scene_.textures[size_t(ref.texture)];
    const Vec2 a = scene_.cornerTextureUv(ref, e.index, 1) - scene_.cornerTextureUv(ref, e.index, 0);
    const Vec2 b = scene_.cornerTextureUv(ref, e.index, 2) - scene_.cornerTextureUv(ref, e.index, 0);
    const float texels = 0.5f * std::abs(a.x * b.y - a.y * b.x) * float(tex.width()) * float(tex.height());
    const int side = std::clamp(int(4.f * std::sqrt(std::min(texels, 1e6f))), 1, kMaxGridSide);
    if (side < 2) return;
    // Each cell's luminance from 2 × 2 points in it.
    std::vector<double> w(size_t(side) * size_t(side));
    double sum = 0.0;
    for (int y = 0; y < side; ++y)
        for (int x = 0; x < side; ++x) {
            double l = 0.0;
            for (int k = 0; k < 4; ++k) {
                const Vec2 q((float(x) + 0.25f + 0.5f * float(k & 1)) / float(side), (float(y) + 0.25f + 0.5f * float(k >> 1)) / float(side));
                const Vec2 bc = sampleUniformTriangle(q);
                l += double(luminance(scene_.emissionAt(material, scene_.attributesAt(e.index, bc.x, bc.y))));
            }
            w[size_t(y * side + x)] = l;
            sum += l;
        }
    const double floor = sum > 0.0 ? kGridFloor * sum / double(w.size()) : 1.0;
    double total = 0.0;
    for (double& v : w) total += (v = std::max(v, floor));
    e.gridSide = uint32_t(side);
    e.gridFirst = uint32_t(cellCdf_.size());
    double acc = 0.0;
    for (double v : w) cellCdf_.push_back(float((acc += v) / total));
    cellCdf_.back() = 1.f;
}

Vec2 LightSampler::sampleOnEmitter(const Entry& e, Vec2 u, float& density) const {
    density = 1.f;
    if (e.gridSide == 0) return sampleUniformTriangle(u);
    const size_t n = size_t(e.gridSide) * e.gridSide;
    const float* cdf = &cellCdf_[e.gridFirst];
    const size_t c = std::min(size_t(std::upper_bound(cdf, cdf + n, u.x) - cdf), n - 1);
    const float lo = c ? cdf[c - 1] : 0.f, p = cdf[c] - lo;
    const float within = p > 0.f ? std::clamp((u.x - lo) / p, 0.f, 0x1.fffffep-1f) : 0.5f;
    density = p * float(n);
    const float side = float(e.gridSide);
    return sampleUniformTriangle(Vec2((float(c % e.gridSide) + within) / side, (float(c / e.gridSide) + u.y) / side));
}

float LightSampler::densityOnEmitter(const Entry& e, Vec2 b) const {
    if (e.gridSide == 0) return 1.f;
    // sampleUniformTriangle's inverse: u.x = (1 − b1)², u.y = b2 / (1 − b1).
    const float s = std::clamp(1.f - b.x, 0.f, 1.f);
    const float qx = s * s, qy = s > 0.f ? std::clamp(b.y / s, 0.f, 1.f) : 0.f;
    const uint32_t side = e.gridSide, x = std::min(uint32_t(qx * float(side)), side - 1);
    const uint32_t y = std::min(uint32_t(qy * float(side)), side - 1), c = y * side + x;
    const float* cdf = &cellCdf_[e.gridFirst];
    return (cdf[c] - (c ? cdf[c - 1] : 0.f)) * float(side * side);
}

size_t LightSampler::choose(float u, float& prob) const {
    size_t i = std::upper_bound(cdf_.begin(), cdf_.end(), u) - cdf_.begin();
    i = std::min(i, cdf_.size() - 1);
    prob = probability(i);
    return i;
}

float LightSampler::portalArea(const Vec3& d) const {
    float a = 0.f;
    for (const PortalTriangle& p : portals_) a += std::abs(glm::dot(p.areaNormal, d));
    return a;
}

bool LightSampler::throughPortal(const Vec3& d, Vec2 u, EmissionSample& s, float& area) const {
    area = portalArea(d);
    if (!(area > 0.f)) return false;
    // The triangle by its projected area; u.x rescaled within its share places the point.
    const float target = u.x * area;
    float acc = 0.f, share = 0.f;
    size_t t = 0;
    for (; t < portals_.size(); ++t) {
        share = std::abs(glm::dot(portals_[t].areaNormal, d));
        if (target < acc + share || t + 1 == portals_.size()) break;
        acc += share;
    }
    const float within = share > 0.f ? std::clamp((target - acc) / share, 0.f, 0x1.fffffep-1f) : 0.5f;
    const PortalTriangle& p = portals_[t];
    const Vec2 b = sampleUniformTriangle(Vec2(within, u.y));
    const Vec3 y = (1.f - b.x - b.y) * p.v0 + b.x * p.v1 + b.y * p.v2;
    // Back along −d to where the line leaves the bounding sphere (a little beyond it).
    const Vec3 c = y - sceneCenter_;
    const float vd = glm::dot(c, d), r = 1.001f * sceneRadius_;
    const float back = vd + std::sqrt(std::max(0.f, vd * vd - (glm::dot(c, c) - r * r)));
    s.origin = y - back * d;
    s.dir = d;
    s.collimated = true;
    return true;
}

float LightSampler::pdfEnvironment(const Vec3& dir) const {
    return environment_ ? probability(size_t(environmentEntry_)) * environment_->pdf(dir) : 0.f;
}

float LightSampler::withinChoice(float u) const {
    float prob;
    const size_t i = choose(u, prob);
    const float lo = i ? cdf_[i - 1] : 0.f;
    return prob > 0.f ? std::clamp((u - lo) / prob, 0.f, 0x1.fffffep-1f) : 0.f;
}

bool LightSampler::wantsBsdfSamples(const Vec3& p, bool glossy) const {
    if (onlyPunctual_) return false;
    if (glossy || environment_ || emitterSpheres_.size() > kMaxNearTests) return true;
    for (const glm::vec4& s : emitterSpheres_) {
        const Vec3 d = p - Vec3(s);
        if (glm::dot(d, d) < s.w * s.w) return true;
    }
    return false;
}

LightSample LightSampler::sampleLi(const Vec3& p, float uChoice, Vec2 u) const {
    LightSample s;
    if (empty()) return s;
    float prob;
    const Entry& e = entries_[choose(uChoice, prob)];
    if (!(prob > 0.f)) return s;
    if (e.kind == Kind::Environment) {
        float pdfDir;
        s.wi = environment_->sample(u, pdfDir);
        if (!(pdfDir > 0.f)) return s;
        s.dist = kInf;
        s.radiance = environment_->radiance(s.wi);
        s.pdf = prob * pdfDir;
        return s;
    }
    if (e.kind == Kind::Area) {
        const Vec3* v = &scene_.positions[3 * e.index];
        float density;
        const Vec2 b = sampleOnEmitter(e, u, density);
        Vec3 pl = (1.f - b.x - b.y) * v[0] + b.x * v[1] + b.y * v[2];
        Vec3 d = pl - p;
        float dist2 = glm::dot(d, d);
        if (!(dist2 > 0.f)) return s;
        s.dist = std::sqrt(dist2);
        s.wi = d / s.dist;
        float cosL = -glm::dot(s.wi, scene_.geometricNormal(e.index));
        if (cosL <= 0.f) return s;  // the back of an emitter is dark
        s.radiance = scene_.emissionAt(scene_.triMaterial[e.index], scene_.attributesAt(e.index, b.x, b.y));
        s.pdf = prob * density * dist2 / (cosL * scene_.triangleArea(e.index));
        return s;
    }
    const PunctualLight& l = scene_.lights[e.index];
    s.delta = true;
    s.pdf = prob;
    if (l.type == LightType::Directional) {
        s.wi = -l.direction;
        s.dist = kInf;
        s.radiance = l.intensity;  // irradiance, W/m², on a surface facing the light
        return s;
    }
    Vec3 d = l.position - p;
    float dist2 = glm::dot(d, d);
    if (!(dist2 > 0.f)) return s;
    s.dist = std::sqrt(dist2);
    s.wi = d / s.dist;
    s.radiance = l.intensityTowards(-s.wi) / dist2;  // irradiance at normal incidence
    return s;
}

float LightSampler::pdfLi(const Vec3& p, uint32_t tri, const Vec3& pl) const {
    int32_t e = entryOfTriangle_[tri];
    if (e < 0) return 0.f;
    float prob = probability(size_t(e));
    Vec3 d = pl - p;
    float dist2 = glm::dot(d, d);
    float cosL = std::abs(glm::dot(d, scene_.geometricNormal(tri))) / std::sqrt(dist2);
    if (cosL <= 0.f) return 0.f;
    float density = 1.f;
    if (entries_[size_t(e)].gridSide > 0) {
        // pl's barycentrics on the triangle.
        const Vec3* v = &scene_.positions[3 * size_t(tri)];
        const Vec3 e1 = v[1] - v[0], e2 = v[2] - v[0], q = pl - v[0];
        const float d00 = glm::dot(e1, e1), d01 = glm::dot(e1, e2), d11 = glm::dot(e2, e2);
        const float d20 = glm::dot(q, e1), d21 = glm::dot(q, e2), den = d00 * d11 - d01 * d01;
        if (den > 0.f)
            density = densityOnEmitter(entries_[size_t(e)], Vec2((d11 * d20 - d01 * d21) / den, (d00 * d21 - d01 * d20) / den));
    }
    return prob * density * dist2 / (cosL * scene_.triangleArea(tri));
}

EmissionSample LightSampler::sampleEmission(float uChoice, Vec2 uPos, Vec2 uDir) const {
    EmissionSample s;
    if (empty()) return s;
    float prob;
    size_t ei = choose(uChoice, prob);
    const Entry& e = entries_[ei];
    s.choiceProb = prob;
    if (!(prob > 0.f)) return s;
    if (e.kind == Kind::Environment) {
        // Like a directional light from a sampled direction: a disc of the scene's bounding
        // radius perpendicular to it, outside the scene; Le·πr² / (pdf(ω)·pChoice).
        float pdfDir;
        const Vec3 wi = environment_->sample(uDir, pdfDir);
        if (!(pdfDir > 0.f)) return s;
        if (hasPortals()) {
            // Through the portals: L·A⊥ / (pdf(ω)·pChoice); none facing ω: no photon.
            float area;
            if (!throughPortal(-wi, uPos, s, area)) return s;
            s.pdfChoicePos = prob / area;
            s.flux = environment_->radiance(wi) * (area / (pdfDir * prob));
            return s;
        }
        Frame f(-wi);
        Vec2 d = sampleUniformDisk(uPos) * sceneRadius_;
        s.origin = sceneCenter_ + sceneRadius_ * wi + d.x * f.s + d.y * f.t;
        s.dir = -wi;
        s.collimated = true;
        s.pdfChoicePos = prob / (kPi * sqr(sceneRadius_));
        s.flux = environment_->radiance(wi) * (kPi * sqr(sceneRadius_) / (pdfDir * prob));
        return s;
    }
    if (e.kind == Kind::Area) {
        // Uniform point on the triangle, cosine-weighted direction around its front normal.
        const Vec3* v = &scene_.positions[3 * e.index];
        float density;
        const Vec2 b = sampleOnEmitter(e, uPos, density);
        Vec3 n = scene_.geometricNormal(e.index);
        s.origin = (1.f - b.x - b.y) * v[0] + b.x * v[1] + b.y * v[2];
        s.normal = n;
        Vec3 local = sampleCosineHemisphere(uDir);
        s.dir = Frame(n).toWorld(local);
        float area = scene_.triangleArea(e.index);
        s.pdfDir = local.z * kInvPi;
        s.pdfChoicePos = prob * density / area;
        // Le·cos / (pChoice · density/A · cos/π) = Le·π·A / (pChoice · density)
        s.flux = scene_.emissionAt(scene_.triMaterial[e.index], scene_.attributesAt(e.index, b.x, b.y)) *
                 (kPi * area / (prob * density));
        return s;
    }
    const PunctualLight& l = scene_.lights[e.index];
    s.pdfChoicePos = prob;
    switch (l.type) {
        case LightType::Point:
        case LightType::Spot: {
            s.origin = l.position;
            if (l.type == LightType::Point) {
                // Uniform over the directions towards the bounds' side along each axis the light
                // lies outside of: a half of the sphere for each such axis.
                s.dir = sampleUniformSphere(uDir);
                s.pdfDir = 1.f / (4.f * kPi);
                for (int a = 0; a < 3; ++a) {
                    if (!e.toward[a]) continue;
                    s.dir[a] = float(e.toward[a]) * std::abs(s.dir[a]);
                    s.pdfDir *= 2.f;
                }
            } else {
                s.dir = Frame(l.direction).toWorld(sampleUniformCone(uDir, l.cosOuter));
                s.pdfDir = 1.f / (2.f * kPi * (1.f - l.cosOuter));
            }
            s.flux = l.intensityTowards(s.dir) / (s.pdfDir * prob);
            break;
        }
        case LightType::Directional: {
            float area;
            if (hasPortals() && throughPortal(l.direction, uPos, s, area)) {
                s.pdfChoicePos = prob / area;
                s.flux = l.intensity * (area / prob);
                break;
            }
            // A disc of the scene's bounding radius, perpendicular to the light, outside the scene.
            Frame f(l.direction);
            Vec2 d = sampleUniformDisk(uPos) * sceneRadius_;
            s.origin = sceneCenter_ - sceneRadius_ * l.direction + d.x * f.s + d.y * f.t;
            s.dir = l.direction;
            s.collimated = true;
            s.pdfChoicePos = prob / (kPi * sqr(sceneRadius_));
            s.flux = l.intensity * (kPi * sqr(sceneRadius_) / prob);
            break;
        }
    }
    return s;
}

}  // namespace rs

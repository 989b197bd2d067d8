#include "eye.h"

namespace rs {

namespace {

Vec2 octWrap(Vec2 v) {
    return (Vec2(1.f) - glm::abs(Vec2(v.y, v.x))) * Vec2(v.x >= 0.f ? 1.f : -1.f, v.y >= 0.f ? 1.f : -1.f);
}

uint32_t quantize(float x) { return uint32_t(std::lround(std::clamp(x * 0.5f + 0.5f, 0.f, 1.f) * 65535.f)); }

}  // namespace

uint32_t encodeUnit(const Vec3& n) {
    Vec3 a = glm::abs(n);
    float l1 = a.x + a.y + a.z;
    Vec2 p = l1 > 0.f ? Vec2(n.x, n.y) / l1 : Vec2(0.f);
    if (n.z < 0.f) p = octWrap(p);
    return quantize(p.x) | (quantize(p.y) << 16);
}

Vec3 decodeUnit(uint32_t e) {
    Vec2 p(float(e & 0xffffu) / 65535.f * 2.f - 1.f, float(e >> 16) / 65535.f * 2.f - 1.f);
    Vec3 n(p.x, p.y, 1.f - std::abs(p.x) - std::abs(p.y));
    float t = std::max(-n.z, 0.f);
    n.x += n.x >= 0.f ? -t : t;
    n.y += n.y >= 0.f ? -t : t;
    return glm::normalize(n);
}

size_t EyeSamples::bytes() const {
    return size() * (sizeof(Vec3) * 2 + sizeof(uint32_t) * 5 + sizeof(Vec2));
}

void EyeSamples::reserve(size_t n) {
    position.reserve(n);
    normal.reserve(n);
    geomNormal.reserve(n);
    toViewer.reserve(n);
    material.reserve(n);
    uv.reserve(n);
    pixel.reserve(n);
    weight.reserve(n);
}

void EyeSamples::append(const EyeSamples& o) {
    position.insert(position.end(), o.position.begin(), o.position.end());
    normal.insert(normal.end(), o.normal.begin(), o.normal.end());
    geomNormal.insert(geomNormal.end(), o.geomNormal.begin(), o.geomNormal.end());
    toViewer.insert(toViewer.end(), o.toViewer.begin(), o.toViewer.end());
    material.insert(material.end(), o.material.begin(), o.material.end());
    uv.insert(uv.end(), o.uv.begin(), o.uv.end());
    pixel.insert(pixel.end(), o.pixel.begin(), o.pixel.end());
    weight.insert(weight.end(), o.weight.begin(), o.weight.end());
}

template <class T>
static void permuteArray(std::vector<T>& v, const std::vector<uint32_t>& order) {
    std::vector<T> out(order.size());
    for (size_t i = 0; i < order.size(); ++i) out[i] = v[order[i]];
    v.swap(out);
}

void EyeSamples::permute(const std::vector<uint32_t>& order) {
    permuteArray(position, order);
    permuteArray(normal, order);
    permuteArray(geomNormal, order);
    permuteArray(toViewer, order);
    permuteArray(material, order);
    permuteArray(uv, order);
    permuteArray(pixel, order);
    permuteArray(weight, order);
}

}  // namespace rs

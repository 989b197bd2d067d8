// The splat stage. Photon rays are processed in chunks on the thread pool; each thread
// accumulates into its own fixed-point buffer (the film's: 2^-32 resolution); the buffers are
// summed into the render's fixed-point film at the end. Integer addition is associative, so the image
// is bit-identical whatever the thread count or scheduling (determinism: docs/design.md §2).
#include "splat/splat.h"

#include <algorithm>
#include <mutex>

#if defined(__SSE2__)
#include <immintrin.h>
#endif

#include "scene/accel.h"
#include "scene/bsdf.h"
#include "scene/scene.h"
#include "core/stats.h"
#include "core/log.h"
#include "core/parallel.h"
#include "splat/pending.h"

namespace rs {

namespace {

constexpr int kSplatLayers = 3;               // direct, indirect, caustic = photon classes
static_assert(int(kPhotonDirect) == int(kDirect) && int(kPhotonIndirect) == int(kIndirect) &&
                  int(kPhotonCaustic) == int(kCaustic),
              "photon classes index the film's layers");

// The 65536 unit vectors of the 16-bit octahedral code, decoded once: the splat decodes two a
// contribution, and a table read (neighbouring samples share their normals) costs less than
// the square root and division of decodeUnit16. Same values, bit for bit.
const Vec3* unitTable() {
    static const std::vector<Vec3> table = [] {
        std::vector<Vec3> t(65536);
        for (uint32_t e = 0; e < t.size(); ++e) t[e] = decodeUnit16(uint16_t(e));
        return t;
    }();
    return table.data();
}

// The order in which photon rays are splatted: by the Morton code of the brick their hit lies
// in, so that consecutive rays read the same part of the tree, the eye samples and the film
// (most of a kernel's receivers lie around the hit). Ties keep the photon order. Any order
// gives the same image: the film sums are integers.
std::vector<uint32_t> coherentOrder(const PhotonMap& photons, const GridGeometry& g) {
    const size_t n = photons.rays.size();
    std::vector<uint64_t> keyed(n);
    for (size_t i = 0; i < n; ++i) {
        const PhotonRay& r = photons.rays[i];
        const Vec3 hit = g.voxelFromWorld(r.origin + r.length * r.dir) / float(kBrickSize);
        uint32_t code = 0;
        for (int a = 0; a < 3; ++a) {
            const float c = std::clamp(hit[a], 0.f, 1023.f);
            code |= spreadBits(uint32_t(c == c ? c : 0.f)) << a;
        }
        keyed[i] = uint64_t(code) << 32 | uint64_t(i);
    }
    std::sort(keyed.begin(), keyed.end());
    std::vector<uint32_t> order(n);
    for (size_t i = 0; i < n; ++i) order[i] = uint32_t(keyed[i]);
    return order;
}

}  // namespace

namespace {

// One photon ray's cylinder (voxel space): it reaches past the hit as far as the kernel lands;
// with visibility it leaves out the samples behind the origin's tangent plane (rule 1).
// With a receiver window that begins past x(i−1), the cylinder begins there too: its walk skips
// the part of a long ray that no sample may receive from, and rule 1, whose plane runs through
// x(i−1), is left to the receive step (there are no occluders to keep in front of it).
Cylinder cylinderOf(const PhotonRay& ray, const GridGeometry& g, bool visibility, bool windowed) {
    const float begin = ray.kernelBegin(windowed);
    Cylinder cyl;
    cyl.origin = g.voxelFromWorld(ray.origin + begin * ray.dir);
    cyl.dir = ray.dir;
    cyl.radius = ray.radius / g.voxelSize;
    cyl.length = (ray.kernelEnd(windowed) - begin) / g.voxelSize;
    cyl.originNormal = ray.originNormal && visibility && begin == 0.f ? decodeUnit(ray.originNormal) : Vec3(0.f);
    return cyl;
}

#if defined(__SSE2__)
// Four samples' vectors, a lane each.
struct Lanes4 {
    __m128 x, y, z;
    static Lanes4 of(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
        return {_mm_setr_ps(a.x, b.x, c.x, d.x), _mm_setr_ps(a.y, b.y, c.y, d.y), _mm_setr_ps(a.z, b.z, c.z, d.z)};
    }
    __m128 dot(const __m128 v[3]) const { return dot4(v, x, y, z); }
};
#endif

// What one photon ray gives each eye sample the traversal hands it: equation (2), after the
// kernel, orientation and receiver tests, into the thread's fixed-point buffer of its class.
class PhotonSplat {
public:
    PhotonSplat(const RayAccel& accel, const EyeSamples& samples, const PhotonRay& ray, const SplatSettings& settings,
                int64_t* layer, SplatStats& stats, const KernelEdge* edge = nullptr)
        : edge_(edge && edge->lines > 0 ? edge : nullptr), least_(settings.minCoverage),
          samples_(samples), ray_(ray), h2_(ray.radius * ray.radius), begin_(ray.kernelBegin(settings.receiverWindow)),
          end_(ray.kernelEnd(settings.receiverWindow)),
          kernelScale_(3.f / (kPi * h2_)), visibility_(settings.visibility), batches_(settings.batches), layer_(layer),
          stats_(stats), receivers_(accel, ray, settings.visibility && settings.visibilityPlanes, settings.receiverWindow),
          pending_(receivers_, stats) {
#if defined(__SSE2__)
        for (int a = 0; a < 3; ++a) {
            four_.origin[a] = _mm_set1_ps(ray.origin[a]), four_.dir[a] = _mm_set1_ps(ray.dir[a]);
            four_.flux[a] = _mm_set1_ps(ray.flux[a]), four_.originNormal[a] = _mm_set1_ps(receivers_.originNormal()[a]);
        }
        four_.begin = _mm_set1_ps(begin_), four_.end = _mm_set1_ps(end_), four_.h2 = _mm_set1_ps(h2_), four_.kernelScale = _mm_set1_ps(kernelScale_);
        if (edge_)
            for (int k = 0; k < 2; ++k)
                for (int a = 0; a < 3; ++a) four_.edge[k][a] = _mm_set1_ps(edge_->e[k][a]);
#endif
    }

    // One sample, whose visibility by the mask is `visibility` (with batches: gathered four at
    // a time for receive4).
    void receive(uint32_t i, float visibility) {
#if defined(__SSE2__)
        if (visibility_ && batches_) {
            waiting_[waitingCount_] = i, waitingV_[waitingCount_] = visibility;
            if (++waitingCount_ == 4) receive4(waiting_, waitingV_, 4), waitingCount_ = 0;
            return;
        }
#endif
        receiveOne(i, visibility);
    }

    // receive() for one sample at once.
    void receiveOne(uint32_t i, float visibility) {
        // Only samples in front of the ray's origin, inside the kernel, facing the photon.
        const Vec3 w = ray_.dir;
        const Vec3 y = samples_.position[i];
        const Vec3 oy = y - ray_.origin;
        const float t = glm::dot(oy, w);
        if (t <= begin_ || t > end_) return;
        const float d2 = glm::dot(oy, oy) - t * t;
        if (d2 >= h2_) return;
        const Vec3 n = units_[samples_.normal[i]];
        const float cosTheta = glm::dot(n, w);
        if (cosTheta >= 0.f) return;
        const Vec3 ng = units_[samples_.geomNormal[i]];
        if (glm::dot(ng, w) >= 0.f) return;
        if (visibility_ && !receivers_.inFrontOfOrigin(y)) {
            ++stats_.refusedBehindOrigin;
            return;
        }
        // Equation (2): w · f_r · Φ · K_h(d⊥) · |n·ω| · V, the sample's w · f_r stored.
        const Vec3 f = samples_.weightedF(i, -w, -cosTheta, shadowing(i));
        float scale = biweightKernel(std::max(d2, 0.f), h2_) * -cosTheta * visibility;
        if (edge_) {
            const float across[2] = {glm::dot(oy, edge_->e[0]), glm::dot(oy, edge_->e[1])};
            scale *= edgeFactor(across);
        }
        const Vec3 c = f * ray_.flux * scale;
        if (!(c.x >= 0.f && c.y >= 0.f && c.z >= 0.f) || !isFinite(c)) return;
        if (visibility_) {
            const Vec3 lifted = SegmentReceivers::lift(y, ng);
            deposit(i, c, receivers_.surelyVisible(lifted), lifted);
        } else {
            deposit(i, c, true, y);
        }
    }

    // Samples the mask gives V > 0: the same as receive(index[k], visibility[k]) for each, whole
    // fours taken straight from the lists where SSE is there.
    void receiveSeen(const uint32_t* index, const float* visibility, size_t count) {
        size_t k = 0;
#if defined(__SSE2__)
        if (visibility_ && batches_) {
            while (waitingCount_ > 0 && k < count) receive(index[k], visibility[k]), ++k;  // the waiting four first
            for (; k + 4 <= count; k += 4) receive4(index + k, visibility + k, 4);
        }
#endif
        for (; k < count; ++k) receive(index[k], visibility[k]);
    }

    // Samples the mask leaves wholly visible (V = 1): the same as receive(i, 1) for each, four
    // at a time where SSE is there.
    void receiveUnshadowed(const uint32_t* index, size_t count) {
#if defined(__SSE2__)
        if (visibility_ && batches_) {
            for (size_t k = 0; k < count; k += 4) receive4(index + k, nullptr, int(std::min<size_t>(4, count - k)));
            return;
        }
#endif
        for (size_t k = 0; k < count; ++k) receiveOne(index[k], 1.f);
    }

    void finish() {
#if defined(__SSE2__)
        if (waitingCount_ > 0) receive4(waiting_, waitingV_, waitingCount_), waitingCount_ = 0;
#endif
        pending_.flush();
    }

private:
    // With kernel edges (kernel_edge.h): 1 / the share of the sample's own kernel on
    // their arriving side, given its e_k·(y − x(i−1)), at most 1 / minCoverage.
    float edgeFactor(const float across[2]) const {
        return 1.f / std::max(edge_->shareAt(across), std::max(least_, 1e-3f));
    }
    // Into the film now when rule 2 is already decided (visible), else when Embree has said.
    void deposit(uint32_t i, const Vec3& c, bool visible, const Vec3& lifted) {
        int64_t* px = &layer_[size_t(samples_.pixel[i]) * 3];
        if (!visible) {
            pending_.add(lifted, px, c);  // Embree decides, a packet at a time
            return;
        }
        if (visibility_) ++stats_.visibleByPlanes;
        addFixed(px, c);
        ++stats_.contributions;
    }
#if defined(__SSE2__)
    void receive4(const uint32_t* index, const float* visibility, int count);
    Lanes4 weightedF4(const uint32_t lane[4], uint32_t live, __m128 minusCos) const;
    // bsdf.h's bumpShadowing of sample i for the photon, 1 where no normal map bent its normal.
    float shadowing(uint32_t i) const {
        const uint16_t ns = samples_.normal[i], ng = samples_.geomNormal[i];
        return !samples_.bumped[i] || ns == ng ? 1.f : bumpShadowing(units_[ng], units_[ns], -ray_.dir);
    }
    void deposit4(const uint32_t lane[4], uint32_t live, const Lanes4& y, const Lanes4& ng, const Lanes4& c);
    uint32_t waiting_[4];  // samples of the sweep waiting for a batch of four
    float waitingV_[4];
    int waitingCount_ = 0;
#endif

    const KernelEdge* const edge_;  // null: none, the photon's flux corrects its kernel's loss
    const float least_;
    const EyeSamples& samples_;
    const Vec3* const units_ = unitTable();
    const PhotonRay& ray_;
    const float h2_, begin_, end_, kernelScale_;  // begin_, end_: the depths that receive
    const bool visibility_, batches_;
    int64_t* layer_;
    SplatStats& stats_;
    const SegmentReceivers receivers_;
    PendingContributions<SegmentReceivers, SplatStats> pending_;
#if defined(__SSE2__)
    struct FourLanes {  // the ray's numbers for receive4, each in all four lanes, set once a photon
        __m128 origin[3], dir[3], flux[3], originNormal[3], begin, end, h2, kernelScale, edge[2][3];
    } four_;
#endif
};

#if defined(__SSE2__)
// receiveOne(index[k], visibility[k] or 1) for up to four samples (with visibility): every step
// the same operations in the same order, one lane a sample, so the same sums; the BSDF is read
// lane by lane, and so are the kernel edges' shares. Lanes4 past `count` repeat the first sample and
// are dropped.
void PhotonSplat::receive4(const uint32_t* index, const float* visibility, int count) {
    const uint32_t lane[4] = {index[0], count > 1 ? index[1] : index[0], count > 2 ? index[2] : index[0],
                              count > 3 ? index[3] : index[0]};
    const Vec3* pos = samples_.position.data();
    const Lanes4 y = Lanes4::of(pos[lane[0]], pos[lane[1]], pos[lane[2]], pos[lane[3]]);
    const uint16_t* nc = samples_.normal.data();
    const uint16_t* gc = samples_.geomNormal.data();
    const Lanes4 n = Lanes4::of(units_[nc[lane[0]]], units_[nc[lane[1]]], units_[nc[lane[2]]], units_[nc[lane[3]]]);
    const Lanes4 ng = Lanes4::of(units_[gc[lane[0]]], units_[gc[lane[1]]], units_[gc[lane[2]]], units_[gc[lane[3]]]);
    const Lanes4 oy{_mm_sub_ps(y.x, four_.origin[0]), _mm_sub_ps(y.y, four_.origin[1]), _mm_sub_ps(y.z, four_.origin[2])};
    const __m128 zero = _mm_setzero_ps();
    // Inside the kernel, facing the photon (negated rejections: a NaN is rejected).
    const __m128 t = oy.dot(four_.dir);
    __m128 ok = _mm_and_ps(_mm_cmpnle_ps(t, four_.begin), _mm_cmpngt_ps(t, four_.end));
    const __m128 d2 = _mm_sub_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(oy.x, oy.x), _mm_mul_ps(oy.y, oy.y)), _mm_mul_ps(oy.z, oy.z)),
                                 _mm_mul_ps(t, t));
    ok = _mm_and_ps(ok, _mm_cmpnge_ps(d2, four_.h2));
    const __m128 cosTheta = n.dot(four_.dir);
    ok = _mm_and_ps(ok, _mm_cmpnge_ps(cosTheta, zero));
    ok = _mm_and_ps(ok, _mm_cmpnge_ps(ng.dot(four_.dir), zero));
    uint32_t live = uint32_t(_mm_movemask_ps(ok)) & ((1u << count) - 1u);
    if (!live) return;
    // Rule 1: in front of the origin's tangent plane.
    const uint32_t front = receivers_.hasOriginNormal() ? uint32_t(_mm_movemask_ps(_mm_cmpgt_ps(oy.dot(four_.originNormal), zero))) : 15u;
    if (const uint32_t behind = live & ~front) stats_.refusedBehindOrigin += uint64_t(__builtin_popcount(behind));
    live &= front;
    if (!live) return;
    // Equation (2): w · f_r · Φ · biweightKernel(max(d2, 0), h2) · −cos θ · V.
    const __m128 x = _mm_sub_ps(_mm_set1_ps(1.f), _mm_div_ps(_mm_max_ps(d2, zero), four_.h2));
    const __m128 kernel = _mm_and_ps(_mm_cmpnle_ps(x, zero), _mm_mul_ps(_mm_mul_ps(four_.kernelScale, x), x));
    const __m128 minusCos = _mm_sub_ps(zero, cosTheta);
    const __m128 v = visibility ? _mm_setr_ps(visibility[0], count > 1 ? visibility[1] : 1.f, count > 2 ? visibility[2] : 1.f,
                                              count > 3 ? visibility[3] : 1.f)
                                : _mm_set1_ps(1.f);
    __m128 scale = _mm_mul_ps(_mm_mul_ps(kernel, minusCos), v);
    if (edge_) {
        alignas(16) float across[2][4], factor[4];
        _mm_store_ps(across[0], oy.dot(four_.edge[0]));
        _mm_store_ps(across[1], oy.dot(four_.edge[1]));
        for (int k = 0; k < 4; ++k) {
            const float a[2] = {across[0][k], across[1][k]};
            factor[k] = edgeFactor(a);
        }
        scale = _mm_mul_ps(scale, _mm_load_ps(factor));
    }
    const Lanes4 f = weightedF4(lane, live, minusCos);
    const Lanes4 c{_mm_mul_ps(_mm_mul_ps(f.x, four_.flux[0]), scale), _mm_mul_ps(_mm_mul_ps(f.y, four_.flux[1]), scale),
                  _mm_mul_ps(_mm_mul_ps(f.z, four_.flux[2]), scale)};
    // Non-negative and finite.
    const __m128 inf = _mm_set1_ps(INFINITY);
    __m128 good = _mm_and_ps(_mm_and_ps(_mm_cmpge_ps(c.x, zero), _mm_cmplt_ps(c.x, inf)),
                             _mm_and_ps(_mm_cmpge_ps(c.y, zero), _mm_cmplt_ps(c.y, inf)));
    good = _mm_and_ps(good, _mm_and_ps(_mm_cmpge_ps(c.z, zero), _mm_cmplt_ps(c.z, inf)));
    live &= uint32_t(_mm_movemask_ps(good));
    if (live) deposit4(lane, live, y, ng, c);
}

// The samples' w · f_r: a Lambert sample's is stored whole (decodeRgb9e5, four lanes at once);
// a glossy one's lobe is evaluated lane by lane.
Lanes4 PhotonSplat::weightedF4(const uint32_t lane[4], uint32_t live, __m128 minusCos) const {
    const uint32_t* bsdf = samples_.bsdf.data();
    const __m128i word = _mm_setr_epi32(int(bsdf[lane[0]]), int(bsdf[lane[1]]), int(bsdf[lane[2]]), int(bsdf[lane[3]]));
    const __m128i nine = _mm_set1_epi32(511);
    const __m128 unit = _mm_castsi128_ps(_mm_slli_epi32(_mm_add_epi32(_mm_srli_epi32(word, 27), _mm_set1_epi32(127 - 24)), 23));
    Lanes4 f{_mm_mul_ps(_mm_cvtepi32_ps(_mm_and_si128(word, nine)), unit),
            _mm_mul_ps(_mm_cvtepi32_ps(_mm_and_si128(_mm_srli_epi32(word, 9), nine)), unit),
            _mm_mul_ps(_mm_cvtepi32_ps(_mm_and_si128(_mm_srli_epi32(word, 18), nine)), unit)};
    alignas(16) float share[4] = {1.f, 1.f, 1.f, 1.f};
    for (uint32_t bits = live; bits; bits &= bits - 1) share[__builtin_ctz(bits)] = shadowing(lane[__builtin_ctz(bits)]);
    const __m128 shares = _mm_load_ps(share);
    f = {_mm_mul_ps(f.x, shares), _mm_mul_ps(f.y, shares), _mm_mul_ps(f.z, shares)};
    const uint32_t glossy = live & uint32_t(_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(_mm_srli_epi32(word, 27), _mm_set1_epi32(31)))));
    if (glossy) {
        alignas(16) float mc[4], fx[4], fy[4], fz[4];
        _mm_store_ps(mc, minusCos);
        _mm_store_ps(fx, f.x), _mm_store_ps(fy, f.y), _mm_store_ps(fz, f.z);
        for (uint32_t bits = glossy; bits; bits &= bits - 1) {
            const int k = __builtin_ctz(bits);
            const Vec3 g = samples_.glossyF(bsdf[lane[k]], -ray_.dir, mc[k], share[k]);
            fx[k] = g.x, fy[k] = g.y, fz[k] = g.z;
        }
        f = {_mm_load_ps(fx), _mm_load_ps(fy), _mm_load_ps(fz)};
    }
    return f;
}

// Rule 2 for the live lanes, lifted off their surfaces (SegmentReceivers::lift): into the film
// when the triangles near the cylinder decide it, else to Embree.
void PhotonSplat::deposit4(const uint32_t lane[4], uint32_t live, const Lanes4& y, const Lanes4& ng, const Lanes4& c) {
    const __m128 absMask = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
    const __m128 largest = _mm_max_ps(_mm_and_ps(y.x, absMask), _mm_max_ps(_mm_and_ps(y.y, absMask), _mm_and_ps(y.z, absMask)));
    const __m128 lift = _mm_mul_ps(_mm_set1_ps(1e-4f), _mm_add_ps(_mm_set1_ps(1.f), largest));
    const Lanes4 lifted{_mm_add_ps(y.x, _mm_mul_ps(lift, ng.x)), _mm_add_ps(y.y, _mm_mul_ps(lift, ng.y)),
                       _mm_add_ps(y.z, _mm_mul_ps(lift, ng.z))};
    const uint32_t visible = receivers_.surelyVisible4(lifted.x, lifted.y, lifted.z);
    alignas(16) float cx[4], cy[4], cz[4], lx[4], ly[4], lz[4];
    _mm_store_ps(cx, c.x), _mm_store_ps(cy, c.y), _mm_store_ps(cz, c.z);
    _mm_store_ps(lx, lifted.x), _mm_store_ps(ly, lifted.y), _mm_store_ps(lz, lifted.z);
    // Counted once here: a count kept in stats_ would be reloaded after every film write (the
    // film's int64_t may alias its uint64_t).
    const uint32_t sure = live & visible;
    static const uint8_t kCount[16] = {0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4};
    stats_.visibleByPlanes += kCount[sure], stats_.contributions += kCount[sure];
    const uint32_t* pixel = samples_.pixel.data();
    for (uint32_t bits = live; bits; bits &= bits - 1) {
        const int k = __builtin_ctz(bits);
        int64_t* px = &layer_[size_t(pixel[lane[k]]) * 3];
        if (sure >> k & 1u)
            addFixed(px, Vec3(cx[k], cy[k], cz[k]));
        else
            pending_.add(Vec3(lx[k], ly[k], lz[k]), px, Vec3(cx[k], cy[k], cz[k]));
    }
}
#endif

// The samples a photon's cylinder reached, with their mask visibility (1 with visibility by
// rays), in the traversal's order: kept while the photon's coverage is measured.
struct ReachedSamples {
    std::vector<uint32_t> index;
    std::vector<float> visibility;

    void clear() { index.clear(), visibility.clear(); }
    auto visitor() {
        return Overloaded{[this](uint32_t i, float v) { index.push_back(i), visibility.push_back(v); },
                          [this](const uint32_t* i, size_t count) {
                              index.insert(index.end(), i, i + count);
                              visibility.insert(visibility.end(), count, 1.f);
                          },
                          [this](const uint32_t* i, const float* v, size_t count) {
                              index.insert(index.end(), i, i + count);
                              visibility.insert(visibility.end(), v, v + count);
                          }};
    }
    // The samples `index` finds in the ray's cylinder, each wholly visible (as the tree hands
    // them where it holds no occluders).
    void find(const CylinderIndex& index, const PhotonRay& ray, bool windowed, TraversalStats& stats) {
        CylinderIndex::Counts counts;
        index.query(ray.origin, ray.dir, ray.radius, ray.kernelBegin(windowed), ray.kernelEnd(windowed), this->index, counts);
        visibility.assign(this->index.size(), 1.f);
        ++stats.cylinders;
        stats.nodes += counts.boxes;
        stats.samplesTested += counts.points;
        stats.samplesReached += this->index.size();
    }
    // Whether one of them lies in the kernel and its window, faces the photon and lies in front
    // of the surface it leaves (PhotonSplat::receiveOne's tests before rule 2).
    // (Rule 1 only with visibility, as the splat.)
    bool anyFacing(const EyeSamples& samples, const PhotonRay& ray, bool windowed, bool visibility) const {
        const float begin = ray.kernelBegin(windowed), end = ray.kernelEnd(windowed), h2 = ray.radius * ray.radius;
        const Vec3* units = unitTable();
        const Vec3 originNormal = ray.originNormal ? decodeUnit(ray.originNormal) : Vec3(0.f);
        for (uint32_t i : index) {
            const Vec3 oy = samples.position[i] - ray.origin;
            const float t = glm::dot(oy, ray.dir);
            if (!(t > begin && t <= end) || !(glm::dot(oy, oy) - t * t < h2)) continue;
            if (visibility && ray.originNormal && !(glm::dot(oy, originNormal) > 0.f)) continue;
            if (glm::dot(units[samples.normal[i]], ray.dir) < 0.f && glm::dot(units[samples.geomNormal[i]], ray.dir) < 0.f)
                return true;
        }
        return false;
    }
};

// Per thread, a fixed-point buffer of pixel × RGB for each photon class the map holds (a pass's
// caustic photons alone take no room for the other two), summed into the film's layers.
struct ThreadLayers {
    int slot[kSplatLayers] = {-1, -1, -1};  // class → its buffer in a thread's, −1: none
    int count = 0;
    size_t values = 0;  // a buffer's: pixels × 3

    ThreadLayers(const PhotonMap& photons, size_t pixels) : values(pixels * 3) {
        for (const PhotonRay& r : photons.rays)
            if (slot[r.cls] < 0) slot[r.cls] = count++;
    }
    int64_t* layer(std::vector<int64_t>& buf, int cls) const {
        if (buf.empty()) buf.assign(size_t(count) * values, 0);
        return &buf[size_t(slot[cls]) * values];
    }
    // Sums the threads' buffers (integers: any order gives the same sum) into the film's layers.
    void addTo(const std::vector<std::vector<int64_t>>& acc, FixedFilm& film) const {
        for (const std::vector<int64_t>& buf : acc) {
            if (buf.empty()) continue;
            for (int l = 0; l < kSplatLayers; ++l) {
                if (slot[l] < 0) continue;
                const int64_t* from = &buf[size_t(slot[l]) * values];
                std::vector<int64_t>& to = film.buffers[l];
                for (size_t i = 0; i < to.size(); ++i) FixedFilm::addSaturating(to[i], from[i]);
            }
        }
    }
};

}  // namespace

void splatPhotons(const RayAccel& accel, const OcclusionTree& tree, const EyeSamples& samples,
                  const PhotonMap& photons, const SplatSettings& settings, FixedFilm& film, ThreadPool& pool,
                  Reporter& reporter, SplatStats* statsOut, CoverageStats* coverageOut) {
    const size_t pixels = film.pixelCount();
    const int threads = pool.size();
    const ThreadLayers layers(photons, pixels);
    std::vector<std::vector<int64_t>> acc(threads);  // per thread: its classes' layers, pixel × rgb
    std::vector<TraversalScratch> scratch(threads);
    std::vector<SplatStats> stats(threads);
    const std::vector<uint32_t> order = coherentOrder(photons, tree.geometry);
    const int64_t chunks = (int64_t(photons.rays.size()) + SplatSettings::kChunk - 1) / SplatSettings::kChunk;
    const int64_t first = std::min(int64_t(photons.rays.size()), chunks * settings.share / settings.shares * SplatSettings::kChunk);
    const int64_t last = std::min(int64_t(photons.rays.size()), chunks * (settings.share + 1) / settings.shares * SplatSettings::kChunk);

    std::vector<ReachedSamples> reached(threads);
    std::vector<CoverageStats> coverage(threads);
    reporter.begin("splatting", last - first, "photons");
    pool.parallelFor(last - first, SplatSettings::kChunk, [&](int64_t b, int64_t e, int thread) {
        for (int64_t p = first + b; p < first + e; ++p) {
            PhotonRay ray = photons.rays[order[size_t(p)]];
            int64_t* layer = layers.layer(acc[thread], ray.cls);
            // A stored photon's coverage is measured already, its edges kept beside it.
            const KernelEdge* stored = photons.edges.empty() ? nullptr : &photons.edges[order[size_t(p)]];
            // The tree's walk needs the cylinder in voxels; the index takes the ray as it is.
            const auto cylinder = [&] { return cylinderOf(ray, tree.geometry, settings.visibility, settings.receiverWindow); };
            if (settings.coverage || settings.index) {
                // The samples first, then the coverage where one of them may take light, then the
                // light, with the kernel the coverage left (the same or halved: inside this cylinder).
                ReachedSamples& r = reached[thread];
                r.clear();
                if (settings.index)
                    r.find(*settings.index, ray, settings.receiverWindow, stats[thread].traversal);
                else
                    traverseCylinder(tree, samples, cylinder(), scratch[thread], r.visitor(), &stats[thread].traversal);
                KernelEdge edge;
                if (settings.coverage) {
                    if (!r.anyFacing(samples, ray, settings.receiverWindow, settings.visibility)) {
                        ++stats[thread].unseen;
                        continue;
                    }
                    normalizeCoverage(accel, ray, *settings.coverage, coverage[thread], &edge);
                }
                PhotonSplat splat(accel, samples, ray, settings, layer, stats[thread], settings.coverage ? &edge : stored);
                splat.receiveSeen(r.index.data(), r.visibility.data(), r.index.size());
                splat.finish();
                continue;
            }
            PhotonSplat splat(accel, samples, ray, settings, layer, stats[thread], stored);
            traverseCylinder(tree, samples, cylinder(), scratch[thread],
                             Overloaded{[&](uint32_t i, float visibility) { splat.receive(i, visibility); },
                                        [&](const uint32_t* index, size_t count) { splat.receiveUnshadowed(index, count); },
                                        [&](const uint32_t* index, const float* visibility, size_t count) {
                                            splat.receiveSeen(index, visibility, count);
                                        }},
                             &stats[thread].traversal);
            splat.finish();
        }
        reporter.advance(e - b);
    });
    reporter.end();
    layers.addTo(acc, film);
    if (statsOut)
        for (const SplatStats& s : stats) statsOut->add(s);
    if (coverageOut)
        for (const CoverageStats& s : coverage) coverageOut->add(s);
}

}  // namespace rs

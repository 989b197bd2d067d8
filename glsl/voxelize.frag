#version 450 core
// Voxelizer fragment stage (docs/design.md §5, paper §4): one fragment = one sub-sample (4×4 per
// voxel face). It sets the bit of the fragment's slice within the current interval of at
// most 64 slices in a 64-bit mask; glLogicOp(GL_OR) accumulates all triangles.
// RG = triangles whose geometric normal points along +axis, BA = along −axis.
//
// The slice comes from the triangle's plane evaluated at the sub-sample centre,
// a = c0 + cu·u + cv·v, with coefficients computed once on the CPU and evaluated in the same
// float operations as voxelize_cpu.cpp ("precise" forbids fused multiply-adds), so the two
// voxelizers agree bit for bit where their coverage agrees. The slice is clamped to the
// triangle's own extent along the axis, as on the CPU.

layout(std430, binding = 0) readonly buffer Planes {
    vec4 planes[];  // 3 per triangle, one per axis: (c0, cu, cv, sign of the normal along the axis)
};
layout(std430, binding = 1) readonly buffer Slices {
    ivec2 slices[];  // 3 per triangle: the slices of its lowest and highest vertex along the axis
};

// Cut-out surfaces (voxelize.h, VoxelTriangles): indexed by the scene's triangle, not the batch's.
layout(std430, binding = 2) readonly buffer Cutouts {
    uint cutouts[];  // per triangle: its cut-out index, or 0xffffffff
};
layout(std430, binding = 3) readonly buffer CutoutPlanes {
    vec4 cutoutPlanes[];  // 6 per cut-out triangle: texture u and v for each axis
};
layout(std430, binding = 4) readonly buffer CutoutInfo {
    uvec4 cutoutInfo[];  // (first level, width, height, 0)
};
layout(std430, binding = 5) readonly buffer Levels {
    uint levels[];
};

flat in uint vTriangle;  // within the bound ranges of the two buffers

uniform int uAxis;
uniform uint uFirstTriangle;
uniform vec2 uTileOrigin;
uniform int uIntervalStart;  // first slice of the interval
uniform int uSliceCount;     // slices in the interval, ≤ 64

layout(location = 0) out uvec4 outMask;

// cutoutHash of voxelize.h.
uint cutoutHash(uint px, uint py, uint axis, uint tri) {
    uint h = (px * 0x8da6b343u) ^ (py * 0xd8163841u) ^ ((tri * 3u + axis) * 0xcb1ab31fu);
    h ^= h >> 15;
    h *= 0x2c1b3c6du;
    h ^= h >> 12;
    h *= 0x297a2d39u;
    h ^= h >> 15;
    return h;
}

// cutoutCovers of voxelize.h: the same float operations, then integers.
bool cutoutCovers(uint c, uint tri, vec2 uv, uvec2 pixel) {
    float tex[2];
    for (uint k = 0u; k < 2u; ++k) {
        vec4 p = cutoutPlanes[c * 6u + uint(uAxis) * 2u + k];
        precise float t = p.y * uv.x;
        precise float s = p.x + t;
        precise float r = p.z * uv.y;
        precise float sum = s + r;
        tex[k] = sum;
    }
    uvec4 info = cutoutInfo[c];
    precise float fx = tex[0] - floor(tex[0]);
    precise float fy = tex[1] - floor(tex[1]);
    precise float sx = fx * float(info.y);
    precise float sy = fy * float(info.z);
    uint x = min(uint(sx), info.y - 1u);
    uint y = min(uint(sy), info.z - 1u);
    return cutoutHash(pixel.x, pixel.y, uint(uAxis), tri) % 255u < levels[info.x + y * info.y + x];
}

void main() {
    uint i = vTriangle * 3u + uint(uAxis);
    vec4 plane = planes[i];
    vec2 range = vec2(slices[i]);
    // Window coordinates are pixel centres (x + 0.5): exact, as is the division by 4.
    vec2 uv = (uTileOrigin + gl_FragCoord.xy) * 0.25;
    precise float t = plane.y * uv.x;
    precise float s = plane.x + t;
    precise float r = plane.z * uv.y;
    precise float a = s + r;
    float slice = clamp(floor(a), range.x, range.y) - float(uIntervalStart);
    if (!(slice >= 0.0 && slice < float(uSliceCount)) || plane.w == 0.0) discard;
    uint tri = vTriangle + uFirstTriangle;
    uint c = cutouts[tri];
    // The window position of a pixel centre is exact (x + 0.5): its integer part is the sub-sample.
    if (c != 0xffffffffu && !cutoutCovers(c, tri, uv, uvec2(uTileOrigin + gl_FragCoord.xy))) discard;
    int k = int(slice);
    uvec2 bit = k < 32 ? uvec2(1u << k, 0u) : uvec2(0u, 1u << (k - 32));
    outMask = plane.w > 0.0 ? uvec4(bit, 0u, 0u) : uvec4(0u, 0u, bit);
}

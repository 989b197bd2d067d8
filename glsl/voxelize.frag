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

flat in uint vTriangle;  // within the bound ranges of the two buffers

uniform int uAxis;
uniform vec2 uTileOrigin;
uniform int uIntervalStart;  // first slice of the interval
uniform int uSliceCount;     // slices in the interval, ≤ 64

layout(location = 0) out uvec4 outMask;

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
    int k = int(slice);
    uvec2 bit = k < 32 ? uvec2(1u << k, 0u) : uvec2(0u, 1u << (k - 32));
    outMask = plane.w > 0.0 ? uvec4(bit, 0u, 0u) : uvec4(0u, 0u, bit);
}

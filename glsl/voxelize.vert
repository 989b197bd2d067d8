#version 450 core
// Voxelizer vertex stage (docs/design.md §5, paper §4): orthographic projection along axis uAxis.
// Positions arrive in voxel space, snapped on the CPU to 1/1024 voxel (= 1/256 pixel at
// 4×4 supersampling, the rasterizer's sub-pixel precision), and this transform is exact in
// float: pixel = 4·p is exact, the viewport (uViewportSize) is a power of two, so NDC and
// window coordinates are too. The rasterizer therefore sees exactly the vertices that
// voxelize_cpu.cpp rasterizes with integer edge functions. Nothing is clipped: depth clamp
// is on, and the viewport covers the whole image (tiles are chosen by its offset and the
// attachment's size) unless the image exceeds GL_MAX_VIEWPORT_DIMS.

layout(location = 0) in vec3 pVoxel;

uniform int uAxis;           // 0, 1, 2: the axis the camera looks along
uniform vec2 uPixelOffset;   // subtracted from the pixel (= sub-sample) position: 0 or the tile's origin
uniform vec2 uViewportSize;  // power of two ≥ the image (or tile), in pixels
uniform vec2 uDepthRange;    // near, far along the axis (voxel units): the interval's bounds
uniform uint uFirstTriangle; // of the batch whose plane and slice buffers are bound

flat out uint vTriangle;

void main() {
    // In-plane axes u = (a+1) mod 3, v = (a+2) mod 3, as in voxelize_cpu.cpp.
    vec3 p = uAxis == 0 ? pVoxel.xyz : uAxis == 1 ? pVoxel.yzx : pVoxel.zxy;  // (a, u, v)
    vec2 pixel = p.yz * 4.0 - uPixelOffset;
    vec2 ndc = pixel * (2.0 / uViewportSize) - 1.0;
    float depth = (p.x - uDepthRange.x) / (uDepthRange.y - uDepthRange.x) * 2.0 - 1.0;
    gl_Position = vec4(ndc, depth, 1.0);
    // The index buffer holds 3t, 3t+1, 3t+2 for triangle t: all three vertices agree.
    vTriangle = uint(gl_VertexID) / 3u - uFirstTriangle;
}

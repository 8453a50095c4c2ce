// The flat attributes from the analytic geometry stage to its fragment stage (one declaration
// for both: RASTER_IO is `out` in raster.geom, `in` in raster.frag).
#ifndef RASTER_IO
#define RASTER_IO out
#endif
layout(location = 0) flat RASTER_IO vec4 g_clip[3];    // the triangle, jittered clip space
layout(location = 3) flat RASTER_IO vec3 g_prev[3];    // previous frame's clip x, y, w
layout(location = 6) flat RASTER_IO vec3 g_world[3];   // camera-relative world positions
layout(location = 9) flat RASTER_IO vec3 g_normal[3];
layout(location = 12) flat RASTER_IO vec4 g_uv01;      // uv of vertices 0 and 1
layout(location = 13) flat RASTER_IO vec2 g_uv2;
layout(location = 14) flat RASTER_IO vec4 g_poly01;    // near-clipped screen polygon, pixels
layout(location = 15) flat RASTER_IO vec4 g_poly23;
layout(location = 16) flat RASTER_IO uvec2 g_info;     // polygon vertex count, primitive ID

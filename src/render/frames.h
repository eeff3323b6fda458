// Frames of many copies of one scene in one call: every copy of a batch drawn into its own
// picture on the thread pool (thread_pool.h), by the rasteriser of raster.h.
//
// The copies share one triangle soup (FrameMesh, made once), one camera and light
// (FrameView), and differ only in the poses of their instances: the bodies' (a World's state
// rows) and the markers' positions. A frame is drawn in four passes:
//   1. every corner moved by its instance's pose (raster_transform);
//   2. the shadow map: the far sides of the shadow casters seen from the light, over the
//      casters' extent across it;
//   3. the opaque triangles through the camera into the z-buffer, then the translucent ones
//      into a layer in front of it;
//   4. shade: colour, Lambert light, shadow and the translucent layer blended over.
// The background (the planes: a table top is most of the triangles and most of the pixels)
// is drawn once into a z-buffer that each frame starts from, and drawn again only when the
// camera or a plane's pose changes: a frame then costs what the moving bodies and the shading
// cost. Each thread draws its copies in buffers of its own, made at the first call (and again
// only when the pool grows), so drawing a frame allocates nothing, and a copy's picture is the
// same bytes whichever thread drew it and whatever else the batch holds (the background's
// z-buffer is exactly what drawing it first into an empty one gives).
#pragma once

#include <cstdint>
#include <vector>

#include "base/math.h"
#include "render/raster.h"
#include "base/span.h"

namespace rg {

// The triangles every copy draws, in drawing order (raster.h's soup: triangle t is corners
// 3t, 3t + 1, 3t + 2): the background (opaque, casting no shadow) first, then the shadow
// casters, then the other opaque triangles, then the translucent ones.
struct FrameMesh {
    Array<Vec3> corners;    // (C,) m, in the frame of the corner's instance
    Array<Vec3> normals;    // (C,) unit shading normals, same frame
    Array<int32_t> owner;   // (C,) instance: body b for b < num_bodies, else marker b - num_bodies
    Array<Vec3> colors;     // (T,) RGB in [0, 1]
    Array<double> alpha;    // (T,) opacity in (0, 1]; below 1 only past num_opaque
    int64_t num_background = 0;  // triangles [0, num_background) are the background
    int64_t num_casters = 0;     // triangles [num_background, + num_casters) cast shadows
    int64_t num_opaque = 0;      // triangles [0, num_opaque) are opaque
    int64_t num_bodies = 0;
    int64_t num_markers = 0;

    int64_t num_triangles() const { return colors.size(); }
};

// The camera and the light, shared by every copy.
struct FrameView {
    Vec3 eye;          // m
    Mat3 axes;         // rows: unit right, up and forward directions
    double focal;      // pixels
    double near;       // m, the near clipping plane's distance from the eye
    Vec3 light;        // unit vector towards the light
    Mat3 light_axes;   // rows u, v (the shadow map's x and y) and `light`
    double ambient;    // brightness of an unlit surface, as a fraction of lit
    Vec3 background;   // RGB in [0, 1] of empty pixels
};

// The poses of every copy's instances. Copy w's bodies are rows [w n, (w + 1) n) of the body
// arrays (a World's state, (B, n, ...)), its markers rows [w m, (w + 1) m) of
// marker_position; the markers' orientations are the same in every copy.
struct FramePoses {
    Span<const Mat3> body_rotation;    // (B n,)
    Span<const Vec3> body_position;    // (B n,) m
    Span<const Mat3> marker_rotation;  // (m,)
    Span<const Vec3> marker_position;  // (B m,) m
};

class FrameRenderer {
public:
    // Frames of `width` x `height` pixels; a shadow map of shadow_side^2 texels (0: no
    // shadows). The mesh's owners must index its instances (the bindings check them).
    FrameRenderer(FrameMesh mesh, int64_t width, int64_t height, int64_t shadow_side);

    // The picture of copy worlds[k] into images rows [k H W, (k + 1) H W) (row-major (H, W)
    // pixels each), the copies shared out over the thread pool. Every index in `worlds` must
    // be a copy of `poses` (the bindings check them).
    void render(const FramePoses& poses, Span<const int64_t> worlds, const FrameView& view,
                Span<Rgb8> images);

    const FrameMesh& mesh() const { return mesh_; }
    int64_t width() const { return width_; }
    int64_t height() const { return height_; }
    int64_t shadow_side() const { return shadow_side_; }

private:
    // One thread's buffers: its copy's instance poses and moved corners, the camera's
    // z-buffer and translucent layer (H, W), the shadow map (S, S), and the background's
    // z-buffer with the view and the background instances' poses it was drawn for.
    struct Scratch {
        Array<Mat3> rotation;
        Array<Vec3> translation;
        Array<Vec3> world, world_normal;
        Array<double> nearness, diffuse, layer_nearness, layer_diffuse, shadow;
        Array<int32_t> ids, layer_ids;
        Array<double> ray_x;  // (W,) shade's scratch
        Array<double> base_nearness, base_diffuse;
        Array<int32_t> base_ids;
        bool base_drawn = false;
        FrameView base_view{};
        Array<Mat3> base_rotation;    // (background instances,)
        Array<Vec3> base_translation;
    };

    Scratch make_scratch() const;
    void draw(const FramePoses& poses, int64_t copy, const FrameView& view, Scratch& s,
              Pixels<Rgb8> image) const;
    // Whether s's background z-buffer was drawn for this view and s's background poses.
    bool background_current(const FrameView& view, const Scratch& s) const;
    void draw_background(const FrameView& view, Scratch& s) const;

    FrameMesh mesh_;
    std::vector<int32_t> background_instances_;  // the instances that own background corners
    int64_t width_, height_, shadow_side_;
    std::vector<Scratch> scratch_;  // one per range of copies
};

}  // namespace rg

// A batch of frames on the thread pool (frames.h).
#include "render/frames.h"

#include <algorithm>
#include <cstring>
#include <utility>

#include "base/thread_pool.h"

namespace rg {

namespace {

// matrix[row] . v.
double dot_row(const Mat3& matrix, int row, Vec3 v) {
    return matrix.m[row][0] * v.x + matrix.m[row][1] * v.y + matrix.m[row][2] * v.z;
}

template <class T>
Pixels<T> pixels(Array<T>& values, int64_t rows, int64_t columns) {
    return {values.span(), rows, columns};
}

template <class T>
Pixels<const T> readable(const Array<T>& values, int64_t rows, int64_t columns) {
    return {values.span(), rows, columns};
}

}  // namespace

FrameRenderer::FrameRenderer(FrameMesh mesh, int64_t width, int64_t height, int64_t shadow_side)
    : mesh_(std::move(mesh)), width_(width), height_(height), shadow_side_(shadow_side) {
    for (int64_t c = 0; c < 3 * mesh_.num_background; ++c) {
        const int32_t owner = mesh_.owner[c];
        if (std::find(background_instances_.begin(), background_instances_.end(), owner) ==
            background_instances_.end()) {
            background_instances_.push_back(owner);
        }
    }
}

FrameRenderer::Scratch FrameRenderer::make_scratch() const {
    const int64_t instances = mesh_.num_bodies + mesh_.num_markers;
    const int64_t corners = mesh_.corners.size(), pixels = width_ * height_;
    Scratch s;
    s.rotation.assign(instances, Mat3{});
    s.translation.assign(instances, Vec3{});
    s.world.assign(corners, Vec3{});
    s.world_normal.assign(corners, Vec3{});
    s.nearness.assign(pixels, 0.0);
    s.diffuse.assign(pixels, 0.0);
    s.layer_nearness.assign(pixels, 0.0);
    s.layer_diffuse.assign(pixels, 0.0);
    s.shadow.assign(shadow_side_ * shadow_side_, 0.0);
    s.ids.assign(pixels, -1);
    s.layer_ids.assign(pixels, -1);
    s.base_nearness.assign(pixels, 0.0);
    s.base_diffuse.assign(pixels, 0.0);
    s.base_ids.assign(pixels, -1);
    s.ray_x.assign(width_, 0.0);
    const int64_t background = static_cast<int64_t>(background_instances_.size());
    s.base_rotation.assign(background, Mat3{});
    s.base_translation.assign(background, Vec3{});
    return s;
}

bool FrameRenderer::background_current(const FrameView& view, const Scratch& s) const {
    // bit for bit: the same bits in give the same z-buffer out
    if (!s.base_drawn || std::memcmp(&view, &s.base_view, sizeof(FrameView)) != 0) {
        return false;
    }
    for (size_t k = 0; k < background_instances_.size(); ++k) {
        const int32_t i = background_instances_[k];
        if (std::memcmp(&s.rotation[i], &s.base_rotation[k], sizeof(Mat3)) != 0 ||
            std::memcmp(&s.translation[i], &s.base_translation[k], sizeof(Vec3)) != 0) {
            return false;
        }
    }
    return true;
}

void FrameRenderer::draw_background(const FrameView& view, Scratch& s) const {
    const int64_t corners = 3 * mesh_.num_background;
    raster_transform(mesh_.corners.span().sub(0, corners), mesh_.normals.span().sub(0, corners),
                     mesh_.owner.span().sub(0, corners), std::as_const(s.rotation).span(),
                     std::as_const(s.translation).span(), s.world.span().sub(0, corners),
                     s.world_normal.span().sub(0, corners));
    std::fill(s.base_nearness.data(), s.base_nearness.data() + s.base_nearness.size(), 0.0);
    std::fill(s.base_ids.data(), s.base_ids.data() + s.base_ids.size(), -1);
    const DepthBuffers base = {pixels(s.base_nearness, height_, width_),
                               pixels(s.base_ids, height_, width_),
                               pixels(s.base_diffuse, height_, width_)};
    rasterize(std::as_const(s.world).span(), std::as_const(s.world_normal).span(), 0,
              mesh_.num_background, view.eye, view.axes, view.focal, view.near, view.light, base);
    for (size_t k = 0; k < background_instances_.size(); ++k) {
        s.base_rotation[k] = s.rotation[background_instances_[k]];
        s.base_translation[k] = s.translation[background_instances_[k]];
    }
    s.base_view = view;
    s.base_drawn = true;
}

void FrameRenderer::render(const FramePoses& poses, Span<const int64_t> worlds,
                           const FrameView& view, Span<Rgb8> images) {
    const int64_t count = worlds.size;
    if (count == 0) {
        return;
    }
    ThreadPool& pool = ThreadPool::instance();
    const int ranges = static_cast<int>(std::min<int64_t>(count, pool.size()));
    while (static_cast<int>(scratch_.size()) < ranges) {
        scratch_.push_back(make_scratch());
    }
    const int64_t size = width_ * height_;
    pool.run(ranges, [&](int range) {
        const int64_t first = count * range / ranges, last = count * (range + 1) / ranges;
        for (int64_t k = first; k < last; ++k) {
            draw(poses, worlds[k], view, scratch_[range],
                 {images.sub(k * size, size), height_, width_});
        }
    });
}

void FrameRenderer::draw(const FramePoses& poses, int64_t copy, const FrameView& view,
                         Scratch& s, Pixels<Rgb8> image) const {
    const FrameMesh& mesh = mesh_;
    const int64_t n = mesh.num_bodies, m = mesh.num_markers;
    for (int64_t b = 0; b < n; ++b) {
        s.rotation[b] = poses.body_rotation[copy * n + b];
        s.translation[b] = poses.body_position[copy * n + b];
    }
    for (int64_t k = 0; k < m; ++k) {
        s.rotation[n + k] = poses.marker_rotation[k];
        s.translation[n + k] = poses.marker_position[copy * m + k];
    }
    if (!background_current(view, s)) {
        draw_background(view, s);
    }
    // the corners past the background: those the background's z-buffer does not hold
    const int64_t first = 3 * mesh.num_background, rest = mesh.corners.size() - first;
    raster_transform(mesh.corners.span().sub(first, rest), mesh.normals.span().sub(first, rest),
                     mesh.owner.span().sub(first, rest), std::as_const(s.rotation).span(),
                     std::as_const(s.translation).span(), s.world.span().sub(first, rest),
                     s.world_normal.span().sub(first, rest));
    const Span<const Vec3> world = std::as_const(s.world).span();
    const Span<const Vec3> world_normal = std::as_const(s.world_normal).span();
    const int64_t casters_first = mesh.num_background;
    const int64_t casters_last = mesh.num_background + mesh.num_casters;

    // The shadow map spans the casters across the light, with two texels to spare on each
    // side; nearness 0 lies 1 m below the lowest caster along the light. Its texels are no
    // finer than half the width that a pixel covers at the nearest caster (finer detail
    // could not show), so it uses only the rows and columns that the casters need: a map
    // costs what the casters' shadows cover in the frame, not shadow_side^2.
    Pixels<const double> shadow{};  // empty: no shadows
    double texel = 1.0;
    Vec3 origin = {0.0, 0.0, 0.0};
    if (shadow_side_ > 0 && mesh.num_casters > 0) {
        Vec3 low = {0.0, 0.0, 0.0}, high = {0.0, 0.0, 0.0};
        double nearest = 0.0;
        for (int64_t c = 3 * casters_first; c < 3 * casters_last; ++c) {
            const Vec3 p = {dot_row(view.light_axes, 0, world[c]),
                            dot_row(view.light_axes, 1, world[c]),
                            dot_row(view.light_axes, 2, world[c])};
            const double depth = dot_row(view.axes, 2, sub(world[c], view.eye));
            const bool first_corner = c == 3 * casters_first;
            low = first_corner ? p : Vec3{std::min(low.x, p.x), std::min(low.y, p.y),
                                          std::min(low.z, p.z)};
            high = first_corner ? p : Vec3{std::max(high.x, p.x), std::max(high.y, p.y),
                                           std::max(high.z, p.z)};
            nearest = first_corner ? depth : std::min(nearest, depth);
        }
        const double finest = 0.5 * std::max(nearest, view.near) / view.focal;
        texel = std::max(std::max(std::max(high.x - low.x, high.y - low.y) /
                                      static_cast<double>(shadow_side_ - 4),
                                  1e-9),
                         finest);
        origin = {low.x - 2.0 * texel, low.y - 2.0 * texel, low.z - 1.0};
        // texels that the casters' span needs, two to spare on each side, at most the side
        // (min's order sends a NaN span, from non-finite poses, to the side)
        const auto needed = [&](double span) {
            return static_cast<int64_t>(
                std::min(static_cast<double>(shadow_side_), std::ceil(span / texel) + 4.0));
        };
        const int64_t columns = needed(high.x - low.x), rows = needed(high.y - low.y);
        std::fill(s.shadow.data(), s.shadow.data() + rows * columns, 0.0);
        const Pixels<double> map = {s.shadow.span().sub(0, rows * columns), rows, columns};
        shadow_map(world, casters_first, casters_last, view.light_axes, origin, texel, map);
        shadow = {std::as_const(s.shadow).span().sub(0, rows * columns), rows, columns};
    }
    // Shadow-map coordinates of eye + depth * axes^T (x, y, 1): texels, texels, m.
    const double scale[3] = {1.0 / texel, 1.0 / texel, 1.0};
    const double origin_of[3] = {origin.x, origin.y, origin.z};
    Mat3 to_light;
    double offset[3];
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) {
            const Vec3 axis = {view.axes.m[c][0], view.axes.m[c][1], view.axes.m[c][2]};
            to_light.m[r][c] = scale[r] * dot_row(view.light_axes, r, axis);
        }
        offset[r] = scale[r] * (dot_row(view.light_axes, r, view.eye) - origin_of[r]);
    }
    const Vec3 light_offset = {offset[0], offset[1], offset[2]};

    std::copy(s.base_nearness.data(), s.base_nearness.data() + s.base_nearness.size(),
              s.nearness.data());
    std::copy(s.base_ids.data(), s.base_ids.data() + s.base_ids.size(), s.ids.data());
    std::copy(s.base_diffuse.data(), s.base_diffuse.data() + s.base_diffuse.size(),
              s.diffuse.data());
    const DepthBuffers opaque = {pixels(s.nearness, height_, width_), pixels(s.ids, height_, width_),
                                 pixels(s.diffuse, height_, width_)};
    rasterize(world, world_normal, mesh.num_background, mesh.num_opaque, view.eye, view.axes,
              view.focal, view.near, view.light, opaque);
    std::fill(s.layer_ids.data(), s.layer_ids.data() + s.layer_ids.size(), -1);
    if (mesh.num_opaque < mesh.num_triangles()) {
        std::copy(s.nearness.data(), s.nearness.data() + s.nearness.size(),
                  s.layer_nearness.data());
        const DepthBuffers layer = {pixels(s.layer_nearness, height_, width_),
                                    pixels(s.layer_ids, height_, width_),
                                    pixels(s.layer_diffuse, height_, width_)};
        rasterize(world, world_normal, mesh.num_opaque, mesh.num_triangles(), view.eye,
                  view.axes, view.focal, view.near, view.light, layer);
    }
    shade(readable(s.nearness, height_, width_), readable(s.ids, height_, width_),
          readable(s.diffuse, height_, width_), readable(s.layer_ids, height_, width_),
          readable(s.layer_diffuse, height_, width_), mesh.colors.span(), mesh.alpha.span(),
          view.focal, to_light, light_offset, texel, shadow, view.ambient, view.background,
          image, s.ray_x.span());
}

}  // namespace rg

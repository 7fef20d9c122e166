//! The UI's opaque base: the solid rectangle egui paints first (the side panel's background), which the
//! compositor fills itself instead of letting egui draw it.
//!
//! egui paints a solid fill through its general shader, a bilinear sample of the font texture's white texel
//! blended over the target; lavapipe (software Vulkan, on the tracer's two cores) spent 10-20 ms of CPU on the
//! panel's background alone at 1280x720 each time the UI layer was drawn again. A scissored draw of one
//! colour writes the same bytes for a fraction of that, as long as the rectangle is egui's first paint
//! (nothing below it to blend with), no other triangle of its mesh reaches inside it, and each pixel whose
//! centre lies on its edge gets the fill's colour from egui too (egui's feathered edge starts at full colour
//! there), since which triangle covers such a pixel is the rasterizer's choice.

use egui::epaint::{Mesh, Primitive, Vertex};
use egui::{ClippedPrimitive, Rect};

use crate::gpu::ui_cover::PixelRect;

/// A solid rectangle of egui's output: its pixels and its colour (egui's premultiplied sRGBA bytes, what its
/// shader writes for them).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolidBase {
    /// Pixels: `x, y, width, height`, never empty.
    pub rect: PixelRect,
    /// Colour bytes.
    pub color: [u8; 4],
}

/// Splits egui's output `jobs` (for a `size` target at `pixels_per_point`) into its solid base, if it has one,
/// and the jobs egui still draws: the same jobs, the first one's mesh without the base's triangles.
pub fn split_solid_base(
    jobs: &[ClippedPrimitive],
    pixels_per_point: f32,
    size: (u32, u32),
) -> (Option<SolidBase>, Vec<ClippedPrimitive>) {
    let mut rest = jobs.to_vec();
    let Some(ClippedPrimitive { clip_rect, primitive: Primitive::Mesh(mesh) }) = rest.first_mut() else {
        return (None, rest);
    };
    match solid_base(mesh, *clip_rect, pixels_per_point, size) {
        Some((base, kept)) => {
            mesh.indices = kept;
            (Some(base), rest)
        }
        None => (None, rest),
    }
}

/// The solid base of `mesh` (egui's first) clipped to `clip`, and the indices of the triangles left to draw.
fn solid_base(mesh: &Mesh, clip: Rect, ppp: f32, size: (u32, u32)) -> Option<(SolidBase, Vec<u32>)> {
    let corners = |t: &[u32]| -> Option<[&Vertex; 3]> {
        Some([mesh.vertices.get(t[0] as usize)?, mesh.vertices.get(t[1] as usize)?, mesh.vertices.get(t[2] as usize)?])
    };
    let solid = |v: &Vertex| v.uv == egui::epaint::WHITE_UV && v.color.a() == 255;
    // The triangles of one opaque colour over the white texel: the base's candidates.
    let first = mesh.indices.chunks_exact(3).filter_map(corners).flatten().find(|v| solid(v))?;
    let color = first.color;
    let of_base = |t: &[&Vertex; 3]| t.iter().all(|v| solid(v) && v.color == color);
    let mut bounds = Rect::NOTHING;
    let mut area = 0.0f64;
    for t in mesh.indices.chunks_exact(3).filter_map(corners).filter(of_base) {
        let [a, b, c] = t.map(|v| v.pos);
        bounds = bounds.union(tri_bounds(&t));
        area += 0.5 * (((b - a).x * (c - a).y - (b - a).y * (c - a).x) as f64).abs();
    }
    // They must tile their bounds exactly.
    let bounds_area = (bounds.width() as f64) * (bounds.height() as f64);
    if !(bounds.width() > 0.0 && bounds.height() > 0.0) || (area - bounds_area).abs() > 1e-3 * bounds_area {
        return None;
    }
    // No other triangle of the mesh may reach inside: the base is drawn before all of them.
    let inside =
        |r: Rect| r.min.x < bounds.max.x && r.max.x > bounds.min.x && r.min.y < bounds.max.y && r.max.y > bounds.min.y;
    let mut kept = Vec::with_capacity(mesh.indices.len());
    // The bounds of the triangles that fade to transparent: egui's feathered edge, when there is one.
    let mut ring = Rect::NOTHING;
    for t in mesh.indices.chunks_exact(3) {
        let vs = corners(t)?;
        if of_base(&vs) {
            continue;
        }
        let r = tri_bounds(&vs);
        if inside(r) {
            return None;
        }
        if vs.iter().any(|v| v.color.a() == 0) {
            ring = ring.union(r);
        }
        kept.extend_from_slice(t);
    }
    // The pixels whose centres lie in the closed rectangle. Those strictly inside are the base's triangles'
    // alone; a centre on an edge may fall to the triangle beyond it (the rasterizer's tie rule), which is
    // only the same colour when it is egui's feathered edge, whose inner side has the fill's full colour.
    let (lo, hi) = (bounds.min * ppp - egui::vec2(0.5, 0.5), bounds.max * ppp - egui::vec2(0.5, 0.5));
    let on_centre = [lo.x, lo.y, hi.x, hi.y].iter().any(|v| v.fract() == 0.0);
    if on_centre && !feathered(&ring, bounds) {
        return None;
    }
    let (x0, y0, x1, y1) = (lo.x.ceil(), lo.y.ceil(), hi.x.floor() + 1.0, hi.y.floor() + 1.0);
    // egui's renderer rounds the clip rectangle to whole pixels for its scissor.
    let clip_px = |v: f32, max: u32| (v * ppp).round().clamp(0.0, max as f32);
    let (cx0, cy0) = (clip_px(clip.min.x, size.0).max(x0), clip_px(clip.min.y, size.1).max(y0));
    let (cx1, cy1) = (clip_px(clip.max.x, size.0).min(x1), clip_px(clip.max.y, size.1).min(y1));
    if !(cx0 < cx1 && cy0 < cy1) {
        return None;
    }
    let rect = [cx0 as u32, cy0 as u32, (cx1 - cx0) as u32, (cy1 - cy0) as u32];
    Some((SolidBase { rect, color: color.to_array() }, kept))
}

/// The parts of a `size` target outside `rect` (which may reach past the target), as at most four disjoint
/// rectangles: the bands above and below it across the whole width, and the parts left and right of it beside
/// it. Under the UI layer's opaque base the traced frame is hidden, so the compositor draws the frame here
/// alone (at 512x512 the side panel covers two thirds of the window).
pub fn around(rect: PixelRect, size: (u32, u32)) -> impl Iterator<Item = PixelRect> {
    let [x, y, w, h] = rect;
    let (x0, y0) = (x.min(size.0), y.min(size.1));
    let (x1, y1) = (x.saturating_add(w).min(size.0), y.saturating_add(h).min(size.1));
    let parts = if x0 >= x1 || y0 >= y1 {
        [[0, 0, size.0, size.1], [0; 4], [0; 4], [0; 4]]
    } else {
        [[0, 0, size.0, y0], [0, y1, size.0, size.1 - y1], [0, y0, x0, y1 - y0], [x1, y0, size.0 - x1, y1 - y0]]
    };
    parts.into_iter().filter(|r| r[2] > 0 && r[3] > 0)
}

/// The bounds of a triangle's corners.
fn tri_bounds(t: &[&Vertex; 3]) -> Rect {
    let [a, b, c] = t.map(|v| v.pos);
    Rect::from_min_max(a.min(b).min(c), a.max(b).max(c))
}

/// Whether `ring` (the bounds of a mesh's fading triangles) reaches beyond `rect` on every side: egui's
/// feathered edge around a fill.
fn feathered(ring: &Rect, rect: Rect) -> bool {
    ring.min.x < rect.min.x && ring.min.y < rect.min.y && ring.max.x > rect.max.x && ring.max.y > rect.max.y
}

#[cfg(test)]
mod tests {
    use egui::epaint::{ClippedShape, RectShape, Shape};
    use egui::{Color32, CornerRadius, StrokeKind, pos2};

    use super::*;

    /// egui's meshes for `shapes`, as its context tessellates them (feathered edges included).
    fn tessellated(shapes: Vec<ClippedShape>, ppp: f32) -> Vec<ClippedPrimitive> {
        let options = egui::epaint::TessellationOptions::default();
        egui::epaint::Tessellator::new(ppp, options, [1, 1], vec![]).tessellate_shapes(shapes)
    }

    fn rect_shape(r: [f32; 4], color: Color32) -> ClippedShape {
        let rect = Rect::from_min_max(pos2(r[0], r[1]), pos2(r[2], r[3]));
        let shape =
            Shape::Rect(RectShape::new(rect, CornerRadius::ZERO, color, egui::Stroke::NONE, StrokeKind::Inside));
        ClippedShape {
            clip_rect: Rect::EVERYTHING,
            shape,
            transform_after_tessellation: egui::emath::TSTransform::IDENTITY,
        }
    }

    const PANEL: Color32 = Color32::from_rgb(27, 27, 27);

    #[test]
    fn a_feathered_panel_background_becomes_a_fill_and_its_edge_stays_with_egui() {
        let jobs = tessellated(vec![rect_shape([0.0, 0.0, 327.0, 720.0], PANEL)], 1.0);
        let Primitive::Mesh(before) = &jobs[0].primitive else { panic!("a mesh") };
        let (base, rest) = split_solid_base(&jobs, 1.0, (1280, 720));
        assert_eq!(base, Some(SolidBase { rect: [0, 0, 327, 720], color: PANEL.to_array() }));
        let Primitive::Mesh(after) = &rest[0].primitive else { panic!("a mesh") };
        assert_eq!(after.vertices, before.vertices);
        assert_eq!(after.indices.len() + 6, before.indices.len(), "the two fill triangles leave");
        assert!(!after.indices.is_empty(), "the feathered edge stays");
        // At two pixels per point the same rectangle still sits on whole pixels.
        let (base, _) =
            split_solid_base(&tessellated(vec![rect_shape([0.0, 0.0, 100.5, 50.0], PANEL)], 2.0), 2.0, (400, 200));
        assert_eq!(base.map(|b| b.rect), Some([0, 0, 201, 100]));
    }

    #[test]
    fn fills_that_egui_must_draw_itself_are_left_alone() {
        let translucent = tessellated(vec![rect_shape([0.0, 0.0, 300.0, 720.0], Color32::from_black_alpha(128))], 1.0);
        let (base, rest) = split_solid_base(&translucent, 1.0, (1280, 720));
        assert_eq!(base, None, "a translucent fill");
        let meshes = |j: &[ClippedPrimitive]| -> Vec<Mesh> {
            j.iter()
                .filter_map(|p| if let Primitive::Mesh(m) = &p.primitive { Some(m.clone()) } else { None })
                .collect()
        };
        assert_eq!(meshes(&rest), meshes(&translucent));
        // Edges through pixel centres without a feathered edge beyond them: which pixels the rasterizer gives
        // the fill is its tie rule's choice.
        let mut hard = Mesh::default();
        hard.add_colored_rect(Rect::from_min_max(pos2(0.5, 0.5), pos2(10.5, 10.5)), PANEL);
        let hard = vec![ClippedPrimitive { clip_rect: Rect::EVERYTHING, primitive: Primitive::Mesh(hard) }];
        assert_eq!(split_solid_base(&hard, 1.0, (64, 64)).0, None, "a hard edge through pixel centres");
        // A feathered fill off whole pixels: the pixels whose centres its inner, opaque part holds.
        let off = tessellated(vec![rect_shape([0.0, 0.0, 327.4, 720.0], PANEL)], 1.0);
        assert_eq!(split_solid_base(&off, 1.0, (1280, 720)).0.map(|b| b.rect), Some([0, 0, 327, 720]));
        // A mesh whose other triangles reach inside the rectangle: the fill would no longer be below them.
        let mut mesh = Mesh::default();
        mesh.add_colored_rect(Rect::from_min_max(pos2(0.0, 0.0), pos2(100.0, 100.0)), PANEL);
        mesh.add_colored_rect(Rect::from_min_max(pos2(10.0, 10.0), pos2(20.0, 20.0)), Color32::from_white_alpha(100));
        let jobs = vec![ClippedPrimitive { clip_rect: Rect::EVERYTHING, primitive: Primitive::Mesh(mesh) }];
        assert_eq!(split_solid_base(&jobs, 1.0, (200, 200)).0, None);
        assert_eq!(split_solid_base(&[], 1.0, (200, 200)).0, None);
    }

    #[test]
    fn around_a_rectangle_covers_every_other_pixel_once() {
        let size = (37, 23);
        let cases = [[0, 0, 12, 23], [5, 4, 10, 7], [30, 0, 20, 23], [0, 20, 37, 3], [0, 0, 37, 23], [40, 5, 3, 3]];
        for rect in cases.into_iter().chain([[2, 3, 0, 5], [u32::MAX, 1, 5, 5]]) {
            let mut count = vec![0u32; (size.0 * size.1) as usize];
            for [x, y, w, h] in around(rect, size) {
                assert!(w > 0 && h > 0 && x + w <= size.0 && y + h <= size.1, "{rect:?}: {:?}", [x, y, w, h]);
                for py in y..y + h {
                    for px in x..x + w {
                        count[(py * size.0 + px) as usize] += 1;
                    }
                }
            }
            let inside = |px: u32, py: u32| {
                let [x, y, w, h] = rect.map(u64::from);
                let (px, py) = (u64::from(px), u64::from(py));
                px >= x && px < x + w && py >= y && py < y + h
            };
            for py in 0..size.1 {
                for px in 0..size.0 {
                    let want = u32::from(!inside(px, py));
                    assert_eq!(count[(py * size.0 + px) as usize], want, "{rect:?}: pixel ({px}, {py})");
                }
            }
        }
    }

    #[test]
    fn the_fill_keeps_to_the_clip_rectangle_and_the_target() {
        let mut mesh = Mesh::default();
        mesh.add_colored_rect(Rect::from_min_max(pos2(0.0, 0.0), pos2(100.0, 100.0)), PANEL);
        let clip = Rect::from_min_max(pos2(10.2, -5.0), pos2(50.7, 60.0));
        let jobs = vec![ClippedPrimitive { clip_rect: clip, primitive: Primitive::Mesh(mesh) }];
        assert_eq!(split_solid_base(&jobs, 1.0, (80, 40)).0.map(|b| b.rect), Some([10, 0, 41, 40]));
    }
}

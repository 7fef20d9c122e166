//! Which pixels of the window a UI frame's egui meshes may touch, as a few disjoint rectangles: the
//! compositor lays the UI layer over these alone, the rest of the layer being transparent.
//!
//! A mesh's bounds are not enough: egui puts everything of one layer and clip rectangle in one mesh, so the
//! side panel's edge line and a readout box in the far corner of the image share a mesh whose bounds span
//! the whole image, and blending over them costs lavapipe (software Vulkan, on the tracer's two cores) a
//! full-window pass every UI frame. Coverage is therefore kept per triangle, in square cells.

use egui::epaint::Primitive;

/// A rectangle of pixels: `x, y, width, height`, as `set_scissor_rect` takes them.
pub type PixelRect = [u32; 4];

/// Edge of the square cells coverage is kept in, in pixels: small enough to follow the panel's and the
/// readouts' outlines, large enough that a frame's few thousand triangles mark few cells each.
const CELL: u32 = 16;

/// Disjoint pixel rectangles, aligned to [`CELL`] and clipped to the `size` target, that cover every pixel
/// the meshes of `jobs` may touch: each triangle's bounds, clipped to its job's clip rectangle and rounded
/// outward (a paint callback may draw anywhere in its clip rectangle). Runs of covered cells along a row
/// become rectangles, and a run continues the rectangle of the row above when it spans the same cells.
pub fn drawn_rects(jobs: &[egui::ClippedPrimitive], pixels_per_point: f32, size: (u32, u32)) -> Vec<PixelRect> {
    let (cols, rows) = (size.0.div_ceil(CELL) as usize, size.1.div_ceil(CELL) as usize);
    let mut covered = vec![false; cols * rows];
    let mut mark = |r: egui::Rect| {
        let (lo, hi) = (r.min * pixels_per_point, r.max * pixels_per_point);
        let (x0, y0) = (lo.x.floor().max(0.0), lo.y.floor().max(0.0));
        let (x1, y1) = (hi.x.ceil().min(size.0 as f32), hi.y.ceil().min(size.1 as f32));
        // Also false for NaN: nothing to mark.
        if !(x0 < x1 && y0 < y1) {
            return;
        }
        let (c0, c1) = (x0 as usize / CELL as usize, (x1 as usize).div_ceil(CELL as usize).min(cols));
        for row in y0 as usize / CELL as usize..(y1 as usize).div_ceil(CELL as usize).min(rows) {
            covered[row * cols + c0..row * cols + c1].fill(true);
        }
    };
    for job in jobs {
        match &job.primitive {
            Primitive::Mesh(m) => {
                for tri in m.indices.chunks_exact(3) {
                    let corners = [tri[0], tri[1], tri[2]].map(|i| m.vertices.get(i as usize).map(|v| v.pos));
                    if let [Some(a), Some(b), Some(c)] = corners {
                        let bounds = egui::Rect::from_min_max(a.min(b).min(c), a.max(b).max(c));
                        mark(bounds.intersect(job.clip_rect));
                    }
                }
            }
            Primitive::Callback(_) => mark(job.clip_rect),
        }
    }
    // Each row's runs of covered cells, `(first, end)`; a run equal to one of the row above extends the
    // rectangle that run belongs to.
    let mut rects: Vec<PixelRect> = Vec::new();
    let mut above: Vec<(usize, usize, usize)> = Vec::new();
    for row in 0..rows {
        let line = &covered[row * cols..(row + 1) * cols];
        let (y, h) = (row as u32 * CELL, CELL.min(size.1 - row as u32 * CELL));
        let mut here = Vec::new();
        let mut col = 0;
        while col < cols {
            if !line[col] {
                col += 1;
                continue;
            }
            let first = col;
            while col < cols && line[col] {
                col += 1;
            }
            let index = match above.iter().find(|&&(f, e, _)| (f, e) == (first, col)) {
                Some(&(_, _, i)) => {
                    rects[i][3] += h;
                    i
                }
                None => {
                    let x = first as u32 * CELL;
                    rects.push([x, y, (col as u32 * CELL).min(size.0) - x, h]);
                    rects.len() - 1
                }
            };
            here.push((first, col, index));
        }
        above = here;
    }
    rects
}

#[cfg(test)]
mod tests {
    use egui::epaint::Mesh;
    use egui::{ClippedPrimitive, Color32, Rect, pos2};

    use super::*;

    /// A job drawing rectangles (in points) in one mesh, clipped to `clip`.
    fn job(shapes: &[[f32; 4]], clip: [f32; 4]) -> ClippedPrimitive {
        let mut mesh = Mesh::default();
        for r in shapes {
            mesh.add_colored_rect(Rect::from_min_max(pos2(r[0], r[1]), pos2(r[2], r[3])), Color32::WHITE);
        }
        ClippedPrimitive {
            clip_rect: Rect::from_min_max(pos2(clip[0], clip[1]), pos2(clip[2], clip[3])),
            primitive: Primitive::Mesh(mesh),
        }
    }

    const WHOLE: [f32; 4] = [0.0, 0.0, 1000.0, 1000.0];

    /// Whether pixel `(x, y)` lies in one of `rects`, and in how many.
    fn count(rects: &[PixelRect], x: u32, y: u32) -> usize {
        rects.iter().filter(|r| x >= r[0] && x < r[0] + r[2] && y >= r[1] && y < r[1] + r[3]).count()
    }

    #[test]
    fn covers_each_shape_once_and_not_the_space_between_shapes_of_one_mesh() {
        // Two points per pixel: a panel at the left, its edge line and a readout box in the far corner, the
        // last two in one mesh (as egui draws them), whose bounds span the whole target.
        let jobs = [
            job(&[[0.0, 0.0, 150.25, 360.0]], WHOLE),
            job(&[[163.0, 0.0, 163.5, 360.0], [560.0, 4.0, 636.0, 40.0]], WHOLE),
        ];
        let size = (1280, 720);
        let rects = drawn_rects(&jobs, 2.0, size);
        for y in 0..size.1 {
            for x in 0..size.0 {
                let c = count(&rects, x, y);
                assert!(c <= 1, "rectangles overlap at ({x}, {y})");
                let (px, py) = (x as f32 / 2.0, y as f32 / 2.0);
                let drawn = px < 150.25 || (163.0..163.5).contains(&px) || (px >= 560.0 && (4.0..40.0).contains(&py));
                assert!(!drawn || c == 1, "drawn pixel ({x}, {y}) not covered");
            }
        }
        assert_eq!(count(&rects, 800, 400), 0, "the image between the panel and the readouts");
        let area: u32 = rects.iter().map(|r| r[2] * r[3]).sum();
        assert!(area < size.0 * size.1 / 3, "{area} pixels blended");
        for r in &rects {
            assert!(r[0] + r[2] <= size.0 && r[1] + r[3] <= size.1 && r[2] > 0 && r[3] > 0, "{r:?}");
        }
    }

    #[test]
    fn clips_to_the_job_and_the_target_and_ignores_broken_meshes() {
        let clipped = drawn_rects(&[job(&[[10.0, 10.0, 20.0, 20.0]], [30.0, 30.0, 40.0, 40.0])], 1.0, (100, 100));
        assert!(clipped.is_empty(), "a shape outside its clip rectangle");
        // The target's edges, which are not multiples of the cell, clip the last cells.
        assert_eq!(drawn_rects(&[job(&[[0.0, 0.0, 900.0, 900.0]], WHOLE)], 1.0, (70, 50)), vec![[0, 0, 70, 50]]);
        let mut broken = Mesh::default();
        broken.add_colored_rect(Rect::from_min_max(pos2(f32::NAN, 0.0), pos2(5.0, 5.0)), Color32::WHITE);
        broken.indices.extend([0, 1, 99]);
        let broken = ClippedPrimitive { clip_rect: Rect::EVERYTHING, primitive: Primitive::Mesh(broken) };
        assert!(drawn_rects(&[broken], 1.0, (64, 64)).is_empty(), "NaN corners and a stray index");
        assert!(drawn_rects(&[], 1.0, (0, 0)).is_empty());
    }

    #[test]
    fn rows_of_equal_runs_merge_into_one_rectangle() {
        let rects = drawn_rects(&[job(&[[3.0, 5.0, 40.0, 90.0]], WHOLE)], 1.0, (128, 128));
        assert_eq!(rects, vec![[0, 0, 48, 96]]);
    }
}

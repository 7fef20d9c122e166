//! The order in which a tile's pixels are traced: scanline, Morton (Z-order) or Hilbert curve (Akenine-Moller
//! and Assarsson, Ray Tracing II: space-filling ray orders keep successive rays close for cache locality).

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

/// Pixel order inside a tile.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RayOrder {
    /// Row by row.
    #[default]
    Scanline,
    /// Z-order: interleaved bits of x and y.
    Morton,
    /// The Hilbert curve, which never jumps between non-adjacent pixels.
    Hilbert,
}

impl RayOrder {
    /// All orders.
    pub const ALL: [RayOrder; 3] = [RayOrder::Scanline, RayOrder::Morton, RayOrder::Hilbert];

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            RayOrder::Scanline => "scanline",
            RayOrder::Morton => "morton",
            RayOrder::Hilbert => "hilbert",
        }
    }

    /// The `(dx, dy)` offsets of a `w x h` tile in this order.
    pub fn offsets(self, w: u32, h: u32) -> Vec<(u32, u32)> {
        let side = w.max(h).max(1).next_power_of_two();
        let inside = |&(x, y): &(u32, u32)| x < w && y < h;
        match self {
            RayOrder::Scanline => (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).collect(),
            RayOrder::Morton => (0..side * side).map(morton_decode).filter(inside).collect(),
            RayOrder::Hilbert => (0..side * side).map(|d| hilbert_decode(side, d)).filter(inside).collect(),
        }
    }
}

impl fmt::Display for RayOrder {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for RayOrder {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        RayOrder::ALL
            .into_iter()
            .find(|o| o.name() == s)
            .ok_or_else(|| format!("unknown ray order '{s}' (valid: scanline, morton, hilbert)"))
    }
}

fn morton_decode(code: u32) -> (u32, u32) {
    let compact = |mut v: u32| {
        v &= 0x5555_5555;
        v = (v | (v >> 1)) & 0x3333_3333;
        v = (v | (v >> 2)) & 0x0f0f_0f0f;
        v = (v | (v >> 4)) & 0x00ff_00ff;
        (v | (v >> 8)) & 0x0000_ffff
    };
    (compact(code), compact(code >> 1))
}

/// Position of step `d` on the Hilbert curve filling a `side x side` square (`side` a power of two).
fn hilbert_decode(side: u32, d: u32) -> (u32, u32) {
    let (mut x, mut y, mut t) = (0u32, 0u32, d);
    let mut s = 1;
    while s < side {
        let rx = 1 & (t / 2);
        let ry = 1 & (t ^ rx);
        if ry == 0 {
            if rx == 1 {
                x = s - 1 - x;
                y = s - 1 - y;
            }
            std::mem::swap(&mut x, &mut y);
        }
        x += s * rx;
        y += s * ry;
        t /= 4;
        s *= 2;
    }
    (x, y)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_order_covers_each_pixel_once() {
        for order in RayOrder::ALL {
            for (w, h) in [(16, 16), (5, 3), (1, 1), (7, 16)] {
                let mut o = order.offsets(w, h);
                assert_eq!(o.len(), (w * h) as usize, "{order} {w}x{h}");
                o.sort();
                o.dedup();
                assert_eq!(o.len(), (w * h) as usize);
            }
        }
    }

    #[test]
    fn hilbert_steps_are_adjacent() {
        let o = RayOrder::Hilbert.offsets(16, 16);
        for p in o.windows(2) {
            let d = p[0].0.abs_diff(p[1].0) + p[0].1.abs_diff(p[1].1);
            assert_eq!(d, 1, "{:?}", p);
        }
        assert_eq!(RayOrder::Morton.offsets(4, 4)[..4], [(0, 0), (1, 0), (0, 1), (1, 1)]);
    }
}

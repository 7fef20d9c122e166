//! Shadow techniques: how much of the light a shaded point sees (Tsakok 2008, chapter 5 and section 4.1.9;
//! the shadow cache of Akenine-Moller and Assarsson, Ray Tracing II).
//!
//! Every technique answers the same question, a visibility in `[0, 1]` per hit point, so the renderer can
//! switch between them per frame and the traversal method only ever changes the speed, never the pixels.

mod cache;
pub(crate) mod samples;

pub use cache::ShadowCache;
pub use samples::{LightSamples, concentric_disc, stratified_grid};

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use glam::Vec3;

use crate::method::Method;
use crate::packet::{Cone, Disc, Frustum};
use crate::trace::Proxy;

/// How the packets of a point's shadow samples are bounded when multi-sampling a spherical light (thesis
/// Figure 4.5, Table 4.6).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SampleBound {
    /// The samples are traced as plain packets: the fastest here for 16 samples or fewer (a bundle of a
    /// few rays spread over a wide light leaves most of its volume unsampled, and a frustum walks all of it).
    #[default]
    Packets,
    /// One pyramid frustum fitted to the point's actual samples (Listing 4.2 over their rays): the tightest
    /// per-axis bound, paid for with a pass over the rays.
    Fitted,
    /// The square pyramid around the light's face seen from the point ([`Frustum::around_disc`]): a proxy
    /// built from the light alone, as the thesis's pyramid.
    Pyramid,
    /// The cone around the light's face seen from the point ([`Cone::around_disc`]): the thesis's cone proxy,
    /// whose per-axis ranges are the disc's own, narrower than a circumscribed square pyramid's.
    Cone,
}

impl SampleBound {
    /// All bounds, in menu order.
    pub const ALL: [SampleBound; 4] =
        [SampleBound::Packets, SampleBound::Fitted, SampleBound::Pyramid, SampleBound::Cone];

    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            SampleBound::Packets => "packets",
            SampleBound::Fitted => "fitted",
            SampleBound::Pyramid => "pyramid",
            SampleBound::Cone => "cone",
        }
    }

    /// A one-line description for menus.
    pub fn summary(self) -> &'static str {
        match self {
            SampleBound::Packets => "each packet of samples walks the tree alone",
            SampleBound::Fitted => "one pyramid fitted to the point's samples (a pass over them)",
            SampleBound::Pyramid => "the square pyramid around the light, built before the samples",
            SampleBound::Cone => "the cone around the light, built before the samples",
        }
    }

    /// The proxy bounding every ray from `apex` to `disc` (where a point's samples lie), for the bounds built
    /// from the light; `None` for the others, or where the apex is too close to the light.
    pub fn proxy(self, apex: Vec3, disc: &Disc) -> Option<Proxy> {
        match self {
            SampleBound::Pyramid => Frustum::around_disc(apex, disc).map(Proxy::Pyramid),
            SampleBound::Cone => Cone::around_disc(apex, disc).map(Proxy::Cone),
            SampleBound::Packets | SampleBound::Fitted => None,
        }
    }

    /// The traversal method that traces one point's samples as a unit where there is no [`Self::proxy`]
    /// (proxies fall back to packets).
    pub fn method(self) -> Method {
        match self {
            SampleBound::Fitted => Method::Frustum,
            SampleBound::Packets | SampleBound::Pyramid | SampleBound::Cone => Method::Packet,
        }
    }
}

impl FromStr for SampleBound {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::ALL
            .into_iter()
            .find(|b| b.name() == s)
            .ok_or_else(|| format!("unknown sample bound '{s}' (expected packets, fitted, pyramid or cone)"))
    }
}

/// The shadow technique of a frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(tag = "technique", rename_all = "kebab-case")]
pub enum Shadows {
    /// No shadow rays; every point sees the light.
    None,
    /// One occlusion ray per point toward the light's centre, traced with the frame's traversal method.
    #[default]
    Hard,
    /// Hard shadows, each shadow ray first tested against the triangle that blocked the previous one in the same
    /// tile (the shadow cache); hits and lookups are counted.
    Cached,
    /// Edge Width Soft Shadows (thesis chapter 5, Listing 5.1): one ray that pairs entry and exit crossings of
    /// closed occluders; the widest pair over `radius` (world units) is the occlusion.
    EdgeWidth {
        /// Edge width at which a point counts as fully occluded; larger values widen the penumbra.
        radius: f32,
        /// Pair entry and exit triangles only when they share a vertex, else count the point as occluded
        /// (the light-leak fix of thesis Figure 5.10).
        leak_fix: bool,
    },
    /// Stratified samples on the spherical light, traced as one bundle per point (thesis Figures 4.5 and 5.2).
    MultiSample {
        /// Samples per point (4, 8, 16 or 32 in the menus; any count from 1 to 4096 works).
        samples: u32,
        /// How each point's samples are bounded.
        bound: SampleBound,
    },
}

impl Shadows {
    /// Most samples per point a multi-sampled technique may ask for.
    pub const MAX_SAMPLES: u32 = 4096;

    /// True when the technique traces any shadow rays.
    pub fn traces(&self) -> bool {
        !matches!(self, Shadows::None)
    }

    /// The short name used on the command line and in tables (`none`, `hard`, `cached`, `edge`, `ms16`).
    pub fn name(&self) -> String {
        match self {
            Shadows::None => "none".into(),
            Shadows::Hard => "hard".into(),
            Shadows::Cached => "cached".into(),
            Shadows::EdgeWidth { .. } => "edge".into(),
            Shadows::MultiSample { samples, .. } => format!("ms{samples}"),
        }
    }

    /// A readable description with the parameters (`edge width, R = 0.6, leak fix`).
    pub fn describe(&self) -> String {
        match self {
            Shadows::EdgeWidth { radius, leak_fix } => {
                format!("edge width, R = {radius}{}", if *leak_fix { ", leak fix" } else { "" })
            }
            Shadows::MultiSample { samples, bound } => format!("{samples} samples, {} bound", bound.name()),
            other => other.name(),
        }
    }

    /// Checks the parameters: a finite, non-negative edge radius and a sample count in `1..=MAX_SAMPLES`.
    pub fn validate(&self) -> Result<(), String> {
        match *self {
            Shadows::EdgeWidth { radius, .. } if !(radius.is_finite() && radius >= 0.0) => {
                Err(format!("edge radius must be a finite number >= 0, got {radius}"))
            }
            Shadows::MultiSample { samples, .. } if !(1..=Self::MAX_SAMPLES).contains(&samples) => {
                Err(format!("shadow samples must be between 1 and {}, got {samples}", Self::MAX_SAMPLES))
            }
            _ => Ok(()),
        }
    }
}

impl fmt::Display for Shadows {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.describe())
    }
}

/// The kind of a shadow technique without its parameters, as the CLI's `--shadows` names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ShadowKind {
    /// [`Shadows::None`].
    None,
    /// [`Shadows::Hard`].
    Hard,
    /// [`Shadows::Cached`].
    Cached,
    /// [`Shadows::EdgeWidth`].
    Edge,
    /// [`Shadows::MultiSample`] with this many samples.
    Samples(u32),
}

impl FromStr for ShadowKind {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let bad =
            || format!("unknown shadow technique '{s}' (expected none, hard, cached, edge, ms4, ms8, ms16 or ms32)");
        Ok(match s {
            "none" => ShadowKind::None,
            "hard" => ShadowKind::Hard,
            "cached" => ShadowKind::Cached,
            "edge" => ShadowKind::Edge,
            _ => {
                let n: u32 = s.strip_prefix("ms").and_then(|n| n.parse().ok()).ok_or_else(bad)?;
                if !(1..=Shadows::MAX_SAMPLES).contains(&n) {
                    return Err(format!("shadow samples in '{s}' must be between 1 and {}", Shadows::MAX_SAMPLES));
                }
                ShadowKind::Samples(n)
            }
        })
    }
}

impl ShadowKind {
    /// The technique with its parameters: the edge radius and leak fix for edge width, the bound for samples.
    pub fn with(self, edge_radius: f32, leak_fix: bool, bound: SampleBound) -> Shadows {
        match self {
            ShadowKind::None => Shadows::None,
            ShadowKind::Hard => Shadows::Hard,
            ShadowKind::Cached => Shadows::Cached,
            ShadowKind::Edge => Shadows::EdgeWidth { radius: edge_radius, leak_fix },
            ShadowKind::Samples(samples) => Shadows::MultiSample { samples, bound },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kinds_parse_and_name_round_trip() {
        for s in ["none", "hard", "cached", "edge", "ms4", "ms8", "ms16", "ms32"] {
            let k: ShadowKind = s.parse().unwrap();
            assert_eq!(k.with(0.5, false, SampleBound::Cone).name(), s);
        }
        assert!("ms0".parse::<ShadowKind>().is_err());
        assert!("ms99999".parse::<ShadowKind>().is_err());
        assert!("soft".parse::<ShadowKind>().unwrap_err().contains("soft"));
        assert_eq!("pyramid".parse::<SampleBound>(), Ok(SampleBound::Pyramid));
        assert!("box".parse::<SampleBound>().is_err());
    }

    #[test]
    fn validation_names_the_bad_value() {
        assert!(Shadows::EdgeWidth { radius: f32::NAN, leak_fix: false }.validate().is_err());
        assert!(Shadows::EdgeWidth { radius: -1.0, leak_fix: false }.validate().is_err());
        assert!(Shadows::MultiSample { samples: 0, bound: SampleBound::Cone }.validate().unwrap_err().contains('0'));
        assert!(Shadows::MultiSample { samples: 32, bound: SampleBound::Cone }.validate().is_ok());
        assert!(Shadows::Hard.validate().is_ok());
    }
}

//! The entries of a bench method list (`--methods`).
//!
//! An entry is a method name, options after colons, and optionally `+fxaa`
//! or `+smaa`:
//!
//! | entry                 | meaning |
//! |-----------------------|---------|
//! | `none`                | a single-sample G-buffer |
//! | `average`             | the naive resolve of the multisampled G-buffer (a hardware resolve) |
//! | `front`, `median`, `back` | the depth-aware resolve with that reference sample |
//! | `per-sample`          | lighting evaluated for every sample (needs renderer support) |
//! | `complex`             | per-sample lighting only on complex pixels (needs renderer support) |
//! | `gbaa`                | geometry-buffer anti-aliasing: a single-sample G-buffer plus edge distances, blended across triangle edges after the tonemap |
//! | `smaa`                | SMAA 1x after the tonemap of a single-sample G-buffer (`none` with `+smaa`); `:preset=low\|medium\|high\|ultra` (default high), `:edges=luma\|color\|depth` (default luma) |
//! | `sparse`              | the multisampled G-buffer as per-pixel linked lists of blocks, one per visible triangle, lit once each (OpenGL 4.3 and post-depth coverage); `:pool=N` sets the pool to N blocks |
//! | `taa`                 | temporal anti-aliasing: one sample per pixel, the projection jittered per frame, the history reprojected, clipped to the neighbourhood and blended; `:alpha=F` (the new frame's weight, default 0.1) and `:phases=N` (Halton jitter phases, default 8). A still frame is measured after the method's warm-up frames ([`AaMode::warmup_frames`]) |
//!
//! Options of the resolve methods: `:hard` / `:smooth` (the closeness
//! window), `:c=F` (outer width; when given without `c_in`, `c_in` becomes
//! `min(2.5, c/2)`), `:c_in=F` (also spelt `c-in`), `:nofast` (no
//! uniform-pixel fast path), `:position-uniformity` and `:plane-uniformity`
//! (the fast path's opt-in tests, `ResolveSettings::position_uniformity` and
//! `plane_uniformity`), `:layers=2` (the second resolved layer, lit by the
//! same lighting pass and mixed in by coverage; front, median and back) and
//! `:normal-threshold=F` (with two layers: the cosine below which two close
//! samples are different surfaces, default 0.95). `+fxaa` after any entry runs the crate's FXAA
//! after tonemapping: `median:hard+fxaa`, `none+fxaa`; `+smaa` runs SMAA 1x
//! instead, with its options after colons: `median+smaa`,
//! `median:layers=2+smaa:preset=ultra`. `:full` after any
//! method renders with every attachment of the layout instead of the
//! scene-adaptive plan (see [`crate::renderer::plan`]): `median` against
//! `median:full` shows what the plan saves (its `gbuffer_bytes`) and costs.
//! `:mix=linear`, `:mix=tonemapped`, `:mix=srgb` or `:mix=curve` after a
//! two-layer method declares what the renderer's lit values are for the
//! second layer's mix (the renderer's own tonemap curve, `curve`, is what
//! it does; the others measure a wrong declaration against the same
//! reference): `median:layers=2:mix=linear`.
//! `:forward` after a method that keeps the multisampled G-buffer
//! (`average`, `front`, `median`, `back`, `per-sample`, `complex`) draws
//! the transparent objects into the retrofit's multisampled forward target
//! instead of single-sampled into the lit image:
//! `median:layers=2:forward`.
//!
//! A run's `method` field in the report is the entry exactly as written.

use crate::renderer::{AaMode, SmaaOptions, technique};
use crate::{Error, Result};
use std::fmt;
use std::str::FromStr;

/// The method list used when `--methods` is not given: these, then
/// [`OPTIONAL_DEFAULT_METHODS`] that the renderer offers.
pub const BASE_DEFAULT_METHODS: &[&str] = &[
    "none",
    "none+fxaa",
    "average",
    "front",
    "median",
    "back",
    "upper-median",
    "median:hard",
    "median:nofast",
    "median+fxaa",
    "gbaa",
    "smaa",
    "median+smaa",
];

/// Default entries that need more than the others.
///
/// `sparse` needs shader storage buffers and post-depth coverage: on a
/// context without them [`run`](super::run) leaves it out of the default
/// list with a warning (a list given with `--methods` fails instead).
pub const OPTIONAL_DEFAULT_METHODS: &[&str] = &["per-sample", "complex", "sparse"];

/// What the accepted entries look like, for error messages: every method
/// name and every technique's options, from the renderer's registry.
fn accepted() -> String {
    let options: Vec<&str> = technique::KINDS
        .iter()
        .filter_map(|k| k.options_help())
        .collect();
    format!(
        "accepted: {}, smaa; options after colons ({}; {}); :full (the full G-buffer layout), :forward (forward MSAA for transparent objects) and +fxaa or +smaa after any entry",
        AaMode::method_names().join(", "),
        options.join("; "),
        SmaaOptions::HELP
    )
}

/// Whether the method's G-buffer pass does more than `none`'s (its
/// `ms_aa` then includes its G-buffer time minus `none`'s).
pub(crate) fn adds_geometry(aa: &AaMode) -> bool {
    technique::kind_of(aa).adds_geometry()
}

/// Whether the method does lighting work beyond the per-pixel pass of
/// `none` (its `ms_aa` then includes its lighting time minus `none`'s).
pub(crate) fn adds_lighting(aa: &AaMode) -> bool {
    technique::kind_of(aa).adds_lighting()
}

/// One entry of a method list: the method, FXAA or SMAA, and the entry as written.
#[derive(Clone, Debug, PartialEq)]
pub struct MethodEntry {
    /// The entry exactly as written (the report's `method` field).
    pub label: String,
    /// The anti-aliasing method with its options, as the renderer takes it.
    pub method: AaMode,
    /// Whether FXAA runs after tonemapping.
    pub fxaa: bool,
    /// SMAA after tonemapping, with its options (`smaa`, `+smaa`).
    pub smaa: Option<SmaaOptions>,
}

impl MethodEntry {
    /// Whether the entry carries `:full`: every attachment of the layout,
    /// not the scene-adaptive plan's.
    pub fn full_layout(&self) -> bool {
        self.has_option("full")
    }

    /// Whether the entry carries `:forward`: the forward passes
    /// (transparent objects) drawn into the retrofit's multisampled
    /// forward target ([`RenderOptions::forward_msaa`](crate::renderer::RenderOptions::forward_msaa)).
    pub fn forward(&self) -> bool {
        self.has_option("forward")
    }

    fn has_option(&self, option: &str) -> bool {
        self.options().any(|o| o == option)
    }

    fn options(&self) -> impl Iterator<Item = &str> {
        let body = self.label.split('+').next().unwrap_or("");
        body.split(':').skip(1)
    }

    /// The entry's `:mix=` declaration of the lit values for the second
    /// layer's mix ([`RenderOptions::layer_mix`](crate::renderer::RenderOptions::layer_mix)),
    /// `None` without one.
    pub fn layer_mix(&self) -> Option<deferred_msaa::LayerMix> {
        self.options()
            .find_map(|o| o.strip_prefix("mix="))
            .and_then(parse_mix)
    }
}

impl fmt::Display for MethodEntry {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.label)
    }
}

impl FromStr for MethodEntry {
    type Err = Error;

    /// Parse one entry (see the [module documentation](self)). The error is
    /// one line that says what is accepted.
    fn from_str(s: &str) -> Result<Self> {
        let label = s.trim();
        if label.is_empty() {
            return Err(Error::invalid(format!(
                "an empty method entry in --methods; {}",
                accepted()
            )));
        }
        let (body, fxaa, mut smaa) = match label.split_once('+') {
            None => (label, false, None),
            Some((body, "fxaa")) => (body, true, None),
            Some((body, post)) if post == "smaa" || post.starts_with("smaa:") => {
                let options: Vec<&str> = post.split(':').skip(1).collect();
                (
                    body,
                    false,
                    Some(SmaaOptions::parse_options(&options, label)?),
                )
            }
            Some((_, other)) => {
                return Err(Error::invalid(format!(
                    "method `{label}`: unknown `+{other}` (only `+fxaa` or `+smaa`, at the end, is accepted); {}",
                    accepted()
                )));
            }
        };
        let mut parts = body.split(':');
        let name = parts.next().unwrap_or("");
        // `:full` is about the layout, `:forward` about the forward passes
        // and `:mix=` about the lit values, not the method: any entry takes
        // them (the renderer refuses `:forward` where the method keeps no
        // multisampled depth).
        let mut options: Vec<&str> = Vec::new();
        for o in parts {
            match o.strip_prefix("mix=") {
                Some(v) => {
                    if parse_mix(v).is_none() {
                        return Err(Error::invalid(format!(
                            "method `{label}`: unknown `mix={v}` (linear, tonemapped, srgb or curve: what the lit values are, for the second layer's mix)"
                        )));
                    }
                }
                None if o == "full" || o == "forward" => {}
                None => options.push(o),
            }
        }
        let method = if name == "smaa" {
            // `smaa` is `none` with SMAA after the tonemap.
            if smaa.is_some() || fxaa {
                return Err(Error::invalid(format!(
                    "method `{label}`: `smaa` is already a post filter; give no `+` after it"
                )));
            }
            smaa = Some(SmaaOptions::parse_options(&options, label)?);
            AaMode::None
        } else {
            let kind = technique::kind_named(name).ok_or_else(|| {
                Error::invalid(format!("unknown method `{label}`; {}", accepted()))
            })?;
            kind.parse(name, &options, label)?
        };
        Ok(MethodEntry {
            label: label.to_string(),
            method,
            fxaa,
            smaa,
        })
    }
}

/// A `:mix=` value: `linear`, `tonemapped`, `srgb` ([`LayerMix::SrgbEncoded`](deferred_msaa::LayerMix::SrgbEncoded))
/// or `curve` (the renderer's own tonemap, its default).
fn parse_mix(v: &str) -> Option<deferred_msaa::LayerMix> {
    use deferred_msaa::LayerMix;
    Some(match v {
        "linear" => LayerMix::Linear,
        "tonemapped" => LayerMix::Tonemapped,
        "srgb" => LayerMix::SrgbEncoded,
        "curve" => LayerMix::Curve(crate::renderer::tonemap_curve()),
        _ => return None,
    })
}

/// Parse a comma-separated method list. Every entry must parse and appear
/// once.
pub fn parse_methods(list: &str) -> Result<Vec<MethodEntry>> {
    let mut entries: Vec<MethodEntry> = Vec::new();
    for item in list.split(',') {
        let entry: MethodEntry = item.parse()?;
        if entries.iter().any(|e| e.label == entry.label) {
            return Err(Error::invalid(format!(
                "method `{}` is listed twice in --methods",
                entry.label
            )));
        }
        entries.push(entry);
    }
    Ok(entries)
}

/// The default method list: [`BASE_DEFAULT_METHODS`], then
/// [`OPTIONAL_DEFAULT_METHODS`].
pub fn default_methods() -> Vec<MethodEntry> {
    BASE_DEFAULT_METHODS
        .iter()
        .chain(OPTIONAL_DEFAULT_METHODS)
        .filter_map(|s| s.parse::<MethodEntry>().ok())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::resolve::{ResolveMethod, ResolveSettings, Window};

    fn settings(e: &MethodEntry) -> ResolveSettings {
        match e.method {
            AaMode::Resolve(s) => s,
            other => panic!("{other:?} is not a resolve"),
        }
    }

    #[test]
    fn forward_and_mix_options_parse_beside_any_method() {
        let e: MethodEntry = "median:layers=2:mix=linear:forward".parse().unwrap();
        assert_eq!(e.layer_mix(), Some(deferred_msaa::LayerMix::Linear));
        assert!(e.forward());
        let e: MethodEntry = "median:layers=2:mix=srgb".parse().unwrap();
        assert_eq!(e.layer_mix(), Some(deferred_msaa::LayerMix::SrgbEncoded));
        assert!(!e.forward());
        let e: MethodEntry = "median:layers=2".parse().unwrap();
        assert_eq!(e.layer_mix(), None);
        let err = "median:layers=2:mix=gamma"
            .parse::<MethodEntry>()
            .unwrap_err()
            .to_string();
        assert!(err.contains("mix=gamma") && !err.contains('\n'), "{err}");
    }

    #[test]
    fn entries_parse_with_options_and_fxaa() {
        let e: MethodEntry = "median:hard+fxaa".parse().unwrap();
        assert_eq!(e.label, "median:hard+fxaa");
        assert!(e.fxaa);
        assert_eq!(settings(&e).window, Window::Hard);
        assert_eq!(settings(&e).method, ResolveMethod::Median);

        let e: MethodEntry = "front:c=3".parse().unwrap();
        assert_eq!((settings(&e).c, settings(&e).c_in), (3.0, 1.5));
        let e: MethodEntry = "back:c=8:c_in=1:nofast".parse().unwrap();
        assert_eq!((settings(&e).c, settings(&e).c_in), (8.0, 1.0));
        assert!(!settings(&e).fast_path);
        let e: MethodEntry = "median:c_in=1".parse().unwrap();
        assert_eq!((settings(&e).c, settings(&e).c_in), (5.0, 1.0));

        let e: MethodEntry = "none+fxaa".parse().unwrap();
        assert_eq!((e.method, e.fxaa), (AaMode::None, true));
        let e: MethodEntry = "gbaa+fxaa".parse().unwrap();
        assert_eq!((e.method, e.fxaa), (AaMode::Gbaa, true));
        assert!(!e.method.takes_samples() && adds_geometry(&e.method));
        assert!("gbaa:hard".parse::<MethodEntry>().is_err());
        let e: MethodEntry = "sparse:pool=16".parse().unwrap();
        match e.method {
            AaMode::Sparse(o) => assert_eq!(o.pool_blocks, Some(16)),
            other => panic!("{other:?} is not sparse"),
        }
        assert!(e.method.takes_samples() && adds_geometry(&e.method) && adds_lighting(&e.method));
        for bad in ["sparse:pool=x", "sparse:hard", "sparse:pool=-1"] {
            let err = bad.parse::<MethodEntry>().unwrap_err().to_string();
            assert_eq!(err.lines().count(), 1, "{bad}: {err}");
        }
        assert_eq!(
            "average".parse::<MethodEntry>().unwrap().method.name(),
            "average"
        );
    }

    #[test]
    fn smaa_is_a_method_and_a_post_filter() {
        use crate::renderer::{SmaaEdges, SmaaPreset};
        let e: MethodEntry = "smaa".parse().unwrap();
        assert_eq!((e.method, e.fxaa), (AaMode::None, false));
        assert_eq!(e.smaa, Some(SmaaOptions::default()));
        let e: MethodEntry = "smaa:preset=ultra:edges=depth".parse().unwrap();
        let o = e.smaa.unwrap();
        assert_eq!((o.preset, o.edges), (SmaaPreset::Ultra, SmaaEdges::Depth));
        let e: MethodEntry = "median:layers=2+smaa:preset=low".parse().unwrap();
        assert!(matches!(e.method, AaMode::Resolve(s) if s.layers == 2));
        assert_eq!(e.smaa.map(|o| o.preset), Some(SmaaPreset::Low));
        let e: MethodEntry = "median+smaa".parse().unwrap();
        assert_eq!(e.smaa, Some(SmaaOptions::default()));
        assert!(!e.fxaa);
        let err = "smaa:preset=extreme"
            .parse::<MethodEntry>()
            .unwrap_err()
            .to_string();
        assert!(err.contains("extreme") && err.contains("ultra"), "{err}");
        let d = default_methods();
        for want in ["smaa", "median+smaa"] {
            assert!(d.iter().any(|e| e.label == want), "{want}");
        }
    }

    #[test]
    fn two_layers_are_a_resolve_option() {
        let e: MethodEntry = "median:layers=2:normal-threshold=0.9+fxaa".parse().unwrap();
        let AaMode::Resolve(settings) = e.method else {
            panic!("{:?}", e.method);
        };
        assert_eq!((settings.layers, settings.normal_threshold), (2, 0.9));
        assert!(e.fxaa);
        let one: MethodEntry = "median".parse().unwrap();
        assert!(matches!(one.method, AaMode::Resolve(s) if s.layers == 1));
    }

    #[test]
    fn bad_entries_are_refused_in_one_line() {
        for bad in [
            "sideways",
            "median:round",
            "median:c=x",
            "median:c=2:c_in=3",
            "none:hard",
            "median+taa",
            "median+fxaa:hard",
            "median+smaa:preset=extreme",
            "smaa:preset=extreme",
            "smaa:hard",
            "smaa+fxaa",
            "smaa+smaa",
            "median:layers=3",
            "average:layers=2",
            "median:normal-threshold=2",
            "",
        ] {
            let e = bad.parse::<MethodEntry>().unwrap_err().to_string();
            assert_eq!(e.lines().count(), 1, "{bad}: {e}");
        }
        let e = "sideways".parse::<MethodEntry>().unwrap_err().to_string();
        assert!(e.contains("sideways") && e.contains("median"), "{e}");
        let e = parse_methods("median,median").unwrap_err().to_string();
        assert!(e.contains("twice"), "{e}");
    }

    #[test]
    fn the_default_list_parses() {
        let d = default_methods();
        assert!(d.len() >= BASE_DEFAULT_METHODS.len());
        assert_eq!(d[0].label, "none");
    }
}

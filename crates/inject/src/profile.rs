//! A per-program profile (TOML): which framebuffer is the G-buffer, what
//! its attachments hold, where the projection comes from, and the
//! retrofit's options: what a program cannot say through its GL calls.
//! docs/inject.md describes every key; `inject --learn` writes a first one.

use deferred_msaa_capi as capi;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Why a profile could not be used.
#[derive(Debug, thiserror::Error)]
pub enum ProfileError {
    /// The file could not be read.
    #[error("cannot read the profile {path}: {source}")]
    Read {
        /// The profile's path.
        path: String,
        /// Why.
        source: std::io::Error,
    },
    /// The file is not a profile.
    #[error("the profile {path} is not valid: {message}")]
    Parse {
        /// The profile's path.
        path: String,
        /// The TOML parser's message, on one line.
        message: String,
    },
    /// A value is out of range.
    #[error("the profile {path}: {message}")]
    Invalid {
        /// The profile's path.
        path: String,
        /// What is wrong.
        message: String,
    },
}

/// A profile: every table optional.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Profile {
    /// Which framebuffer is the G-buffer.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub framebuffer: Option<FramebufferMatch>,
    /// What each colour attachment holds and how its samples become one.
    #[serde(default, rename = "attachment", skip_serializing_if = "Vec::is_empty")]
    pub attachments: Vec<Attachment>,
    /// Where each frame's projection (and view) matrix comes from.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub projection: Option<Projection>,
    /// The retrofit's options.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub retrofit: Option<Retrofit>,
    /// Which pass after the resolve is the lighting (two layers).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lighting: Option<Lighting>,
}

/// The lighting pass the second layer replays.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Lighting {
    /// Its position among the passes after the resolve (each pass: the
    /// draws up to the next framebuffer bind), from 1 (the default).
    pub pass: u32,
    /// How many passes it spans from there (default 1): lights added into
    /// an accumulation target, then a compose into the lit target, are 2.
    /// The lit target is the last pass's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub passes: Option<u32>,
}

/// A framebuffer's attachment signature: a framebuffer that has all of
/// these is the G-buffer, with no need for the heuristic's evidence.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FramebufferMatch {
    /// How many colour attachments are textures.
    pub colour_textures: u32,
    /// Whether it has a depth attachment.
    #[serde(default = "yes")]
    pub depth: bool,
    /// Each colour attachment's component type and bits per channel, as
    /// GL reports them (`"float16"`, `"unorm8"`…), in attachment order;
    /// empty: any.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub formats: Vec<String>,
}

fn yes() -> bool {
    true
}

/// What one colour attachment holds.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Attachment {
    /// The colour attachment number (`GL_COLOR_ATTACHMENTn`).
    pub index: u32,
    /// `"position"` (the depth key), `"normal"` (the normal test), or
    /// anything else (`"albedo"`, `"other"`): no role.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub meaning: Option<String>,
    /// With `meaning = "position"`: world-space positions (the view matrix
    /// is then needed every frame).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub world_space: Option<bool>,
    /// With `meaning = "normal"`: `"xyz"`, `"unorm"`, `"octahedral"`,
    /// `"octahedral-unorm"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub encoding: Option<String>,
    /// `"default"`, `"blend"`, `"blend-normal"`, `"blend-hdr"`, `"select"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rule: Option<String>,
    /// The four values the program clears this attachment to, for a
    /// program whose clear the library cannot follow: the retrofit then
    /// clears its framebuffer to the profile's values at each frame's
    /// start (`clear_twins`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub clear: Option<Vec<f32>>,
}

/// Where the projection comes from: a uniform the program sets, or fixed
/// values.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Projection {
    /// The uniform the program sets it through (`glUniformMatrix4fv`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub uniform: Option<String>,
    /// The view matrix's uniform (world-space positions only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub view_uniform: Option<String>,
    /// A fixed projection, 16 numbers column by column as GL takes them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub matrix: Option<Vec<f32>>,
    /// A fixed view matrix, likewise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub view: Option<Vec<f32>>,
    /// The uniform-buffer binding point (`glBindBufferBase(GL_UNIFORM_BUFFER,
    /// N, …)`) of the block the program keeps its camera in: the matrices
    /// are read from the buffer bound there at each resolve.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub block_binding: Option<u32>,
    /// The projection's byte offset in that block (default 0; std140
    /// keeps a `mat4` as 16 floats, column by column).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub offset: Option<u32>,
    /// The view matrix's byte offset in that block (world-space positions).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub view_offset: Option<u32>,
    /// The uniform the program sets its view-projection product through
    /// (`viewProjection`), in place of a projection and a view: taken
    /// apart into the projection's depth terms and field of view and the
    /// view's z row (a rigid view assumed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub view_projection_uniform: Option<String>,
}

/// Where in a uniform buffer the camera is: the binding point and the
/// byte offsets of the projection and (optionally) the view.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CameraBlock {
    /// The `GL_UNIFORM_BUFFER` binding point.
    pub binding: u32,
    /// The projection's byte offset.
    pub offset: u32,
    /// The view's byte offset.
    pub view_offset: Option<u32>,
}

/// The options of [`capi::DmsaaOptions`] a profile sets; the others keep
/// `dmsaa_options_default`'s values.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Retrofit {
    /// Requested samples per pixel.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub samples: Option<u32>,
    /// 1 or 2 layers.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub layers: Option<u32>,
    /// What the lit values mean: `"auto"`, `"linear"`, `"tonemapped"`,
    /// `"srgb-encoded"`, or `"curve"` with `layer_mix_curve`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub layer_mix: Option<String>,
    /// With `layer_mix = "curve"`: GLSL defining `vec3 dmsaa_curve(vec3)`
    /// (the program's tonemap) and `vec3 dmsaa_curve_inverse(vec3)`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub layer_mix_curve: Option<String>,
    /// `layer_mix_curve` as the C string the options point at, made once:
    /// the profile outlives every retrofit made from it.
    #[serde(skip)]
    curve_c: std::sync::OnceLock<std::ffi::CString>,
    /// `"standard"`, `"zero-to-one"`, `"reversed-z"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub depth_mode: Option<String>,
    /// The colour attachments the second layer need not carry.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub second_layer_omits: Vec<u32>,
    /// Whether the second lighting's occlusion check runs.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub check_second_lighting: Option<bool>,
    /// Whether what the program draws into its lit target after the
    /// lighting goes into the forward target (default true).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub forward: Option<bool>,
    /// The depth the program clears its G-buffer to (with the attachments'
    /// `clear`: the retrofit's framebuffer cleared to them each frame).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub clear_depth: Option<f32>,
    /// The stencil it clears to.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub clear_stencil: Option<i32>,
}

/// The shipped profile for programs written as the LearnOpenGL
/// deferred-shading chapter's (`profiles/tutorial.toml`).
pub const TUTORIAL: &str = include_str!("../profiles/tutorial.toml");

impl Profile {
    /// Read and check the profile at `path`.
    pub fn load(path: &Path) -> Result<Profile, ProfileError> {
        let shown = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| ProfileError::Read {
            path: shown.clone(),
            source,
        })?;
        Profile::parse(&text, &shown)
    }

    /// Parse and check a profile's text; `path` names it in errors.
    pub fn parse(text: &str, path: &str) -> Result<Profile, ProfileError> {
        let profile: Profile = toml::from_str(text).map_err(|e| ProfileError::Parse {
            path: path.to_string(),
            message: e.message().replace('\n', " "),
        })?;
        profile.options(path)?;
        Ok(profile)
    }

    /// The projection's uniform name (`"projection"` unless the profile
    /// names another or gives fixed values).
    pub fn projection_uniform(&self) -> Option<&str> {
        match &self.projection {
            Some(p)
                if p.matrix.is_some()
                    || p.block_binding.is_some()
                    || p.view_projection_uniform.is_some() =>
            {
                None
            }
            Some(Projection {
                uniform: Some(u), ..
            }) => Some(u),
            _ => Some("projection"),
        }
    }

    /// The view matrix's uniform name (`"view"` unless named otherwise or
    /// fixed).
    pub fn view_uniform(&self) -> Option<&str> {
        match &self.projection {
            Some(p)
                if p.view.is_some()
                    || p.view_offset.is_some()
                    || p.view_projection_uniform.is_some() =>
            {
                None
            }
            Some(Projection {
                view_uniform: Some(u),
                ..
            }) => Some(u),
            _ => Some("view"),
        }
    }

    /// The view-projection uniform's name, where the profile names one.
    pub fn view_projection_uniform(&self) -> Option<&str> {
        self.projection.as_ref()?.view_projection_uniform.as_deref()
    }

    /// The uniform block the camera is read from, where the profile names
    /// one.
    pub fn camera_block(&self) -> Option<CameraBlock> {
        let p = self.projection.as_ref()?;
        Some(CameraBlock {
            binding: p.block_binding?,
            offset: p.offset.unwrap_or(0),
            view_offset: p.view_offset,
        })
    }

    /// The fixed projection and view, where the profile gives them.
    pub fn fixed_matrices(&self) -> (Option<[f32; 16]>, Option<[f32; 16]>) {
        let fixed = |m: &Option<Vec<f32>>| m.as_deref().and_then(|v| v.try_into().ok());
        match &self.projection {
            Some(p) => (fixed(&p.matrix), fixed(&p.view)),
            None => (None, None),
        }
    }

    /// The C API's options this profile describes, checked.
    pub fn options(&self, path: &str) -> Result<capi::DmsaaOptions, ProfileError> {
        let bad = |message: String| ProfileError::Invalid {
            path: path.to_string(),
            message,
        };
        let mut options = capi::dmsaa_options_default();
        for a in &self.attachments {
            let k = a.index as usize;
            if k >= capi::DMSAA_MAX_RULES {
                return Err(bad(format!(
                    "attachment index {} is above {}",
                    a.index,
                    capi::DMSAA_MAX_RULES - 1
                )));
            }
            match a.meaning.as_deref() {
                Some("position") => {
                    options.position_attachment = a.index as i32;
                    options.world_space_position = u8::from(a.world_space.unwrap_or(false));
                }
                Some("normal") => {
                    options.normal_attachment = a.index as i32;
                    options.normal_encoding = match a.encoding.as_deref().unwrap_or("xyz") {
                        "xyz" => capi::DMSAA_NORMAL_XYZ,
                        "unorm" => capi::DMSAA_NORMAL_UNORM,
                        "octahedral" => capi::DMSAA_NORMAL_OCTAHEDRAL,
                        "octahedral-unorm" => capi::DMSAA_NORMAL_OCTAHEDRAL_UNORM,
                        other => {
                            return Err(bad(format!(
                                "attachment {}: unknown normal encoding {other:?} (xyz, unorm, octahedral, octahedral-unorm)",
                                a.index
                            )));
                        }
                    };
                }
                _ => {}
            }
            if let Some(clear) = &a.clear {
                let values: [f32; 4] = clear.as_slice().try_into().map_err(|_| {
                    bad(format!(
                        "attachment {}: clear needs 4 numbers, has {}",
                        a.index,
                        clear.len()
                    ))
                })?;
                options.clear_twins = 1;
                options.clear_colors[k] = values;
            }
            if let Some(rule) = &a.rule {
                options.rules[k] = match rule.as_str() {
                    "default" => capi::DMSAA_RULE_DEFAULT,
                    "blend" => capi::DMSAA_RULE_BLEND,
                    "blend-normal" => capi::DMSAA_RULE_BLEND_NORMAL,
                    "blend-hdr" => capi::DMSAA_RULE_BLEND_HDR,
                    "select" => capi::DMSAA_RULE_SELECT,
                    other => {
                        return Err(bad(format!(
                            "attachment {}: unknown rule {other:?} (default, blend, blend-normal, blend-hdr, select)",
                            a.index
                        )));
                    }
                };
            }
        }
        if self.lighting.as_ref().is_some_and(|l| l.pass == 0) {
            return Err(bad("lighting.pass counts from 1".into()));
        }
        if self.lighting.as_ref().is_some_and(|l| l.passes == Some(0)) {
            return Err(bad("lighting.passes is 1 or more".into()));
        }
        if let Some(p) = &self.projection {
            for (name, m) in [("matrix", &p.matrix), ("view", &p.view)] {
                if m.as_ref().is_some_and(|v| v.len() != 16) {
                    return Err(bad(format!("projection.{name} needs 16 numbers")));
                }
            }
        }
        let Some(r) = &self.retrofit else {
            return Ok(options);
        };
        if let Some(samples) = r.samples {
            options.samples = samples;
        }
        if let Some(layers) = r.layers {
            if !(1..=2).contains(&layers) {
                return Err(bad(format!("layers = {layers}: 1 or 2")));
            }
            options.layers = layers;
        }
        if let Some(mix) = &r.layer_mix {
            options.layer_mix = match mix.as_str() {
                "auto" => capi::DMSAA_LAYER_MIX_AUTO,
                "linear" => capi::DMSAA_LAYER_MIX_LINEAR,
                "tonemapped" => capi::DMSAA_LAYER_MIX_TONEMAPPED,
                "srgb-encoded" => capi::DMSAA_LAYER_MIX_SRGB_ENCODED,
                "curve" => capi::DMSAA_LAYER_MIX_CURVE,
                other => {
                    return Err(bad(format!(
                        "unknown layer_mix {other:?} (auto, linear, tonemapped, srgb-encoded, curve)"
                    )));
                }
            };
        }
        match (
            options.layer_mix == capi::DMSAA_LAYER_MIX_CURVE,
            &r.layer_mix_curve,
        ) {
            (true, Some(text)) => {
                let c = std::ffi::CString::new(text.as_str())
                    .map_err(|_| bad("layer_mix_curve holds a NUL character".into()))?;
                options.layer_mix_curve = r.curve_c.get_or_init(|| c).as_ptr();
            }
            (true, None) => {
                return Err(bad(
                    "layer_mix = \"curve\" needs layer_mix_curve: GLSL defining vec3 dmsaa_curve(vec3) and vec3 dmsaa_curve_inverse(vec3)".into(),
                ));
            }
            (false, Some(_)) => {
                return Err(bad(
                    "layer_mix_curve is read only with layer_mix = \"curve\"".into(),
                ));
            }
            (false, None) => {}
        }
        if let Some(mode) = &r.depth_mode {
            options.depth_mode = match mode.as_str() {
                "standard" => capi::DMSAA_DEPTH_STANDARD,
                "zero-to-one" => capi::DMSAA_DEPTH_ZERO_TO_ONE,
                "reversed-z" => capi::DMSAA_DEPTH_REVERSED_Z,
                other => {
                    return Err(bad(format!(
                        "unknown depth_mode {other:?} (standard, zero-to-one, reversed-z)"
                    )));
                }
            };
        }
        for &k in &r.second_layer_omits {
            if k as usize >= capi::DMSAA_MAX_RULES {
                return Err(bad(format!("second_layer_omits: {k} is above 7")));
            }
            options.second_layer_omits |= 1 << k;
        }
        if let Some(check) = r.check_second_lighting {
            options.check_second_lighting = u8::from(check);
        }
        if let Some(depth) = r.clear_depth {
            options.clear_twins = 1;
            options.clear_depth = depth;
        }
        if let Some(stencil) = r.clear_stencil {
            options.clear_twins = 1;
            options.clear_stencil = stencil;
        }
        Ok(options)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shipped_tutorial_profile_gives_the_tutorial_options() {
        let p = Profile::parse(TUTORIAL, "tutorial.toml").expect("the shipped profile parses");
        let o = p.options("tutorial.toml").expect("valid");
        assert_eq!(o.position_attachment, 0);
        assert_eq!(o.world_space_position, 1);
        assert_eq!(o.normal_attachment, 1);
        assert_eq!(o.rules[1], capi::DMSAA_RULE_SELECT);
        assert_eq!(o.layer_mix, capi::DMSAA_LAYER_MIX_SRGB_ENCODED);
        assert_eq!(p.view_uniform(), Some("view"));
    }

    #[test]
    fn stated_clear_values_clear_the_twins() {
        let text = "[[attachment]]\nindex = 2\nclear = [0.0, 0.0, 65504.0, 1.0]\n\n[retrofit]\nclear_depth = 0.0\nforward = false\n";
        let p = Profile::parse(text, "p.toml").expect("parses");
        let o = p.options("p.toml").expect("valid");
        assert_eq!(o.clear_twins, 1);
        assert_eq!(o.clear_colors[2], [0.0, 0.0, 65504.0, 1.0]);
        assert_eq!(o.clear_depth, 0.0);
        assert_eq!(o.clear_stencil, 0);
        assert_eq!(p.retrofit.and_then(|r| r.forward), Some(false));
        let none = Profile::parse(TUTORIAL, "tutorial.toml").expect("parses");
        assert_eq!(none.options("tutorial.toml").expect("valid").clear_twins, 0);
    }

    #[test]
    fn a_curve_is_handed_to_the_library_as_its_text() {
        let curve = "vec3 dmsaa_curve(vec3 x) { return clamp(x * 0.8, 0.0, 1.0); }\nvec3 dmsaa_curve_inverse(vec3 y) { return y / 0.8; }\n";
        let text = format!(
            "[retrofit]\nlayers = 2\nlayer_mix = \"curve\"\nlayer_mix_curve = \"\"\"\n{curve}\"\"\"\n"
        );
        let p = Profile::parse(&text, "p.toml").expect("parses");
        let o = p.options("p.toml").expect("valid");
        assert_eq!(o.layer_mix, capi::DMSAA_LAYER_MIX_CURVE);
        // SAFETY: the pointer is the profile's C string, alive with `p`.
        let handed = unsafe { std::ffi::CStr::from_ptr(o.layer_mix_curve) };
        assert_eq!(handed.to_str().expect("UTF-8"), curve);
    }

    #[test]
    fn bad_values_are_one_line_errors() {
        for (text, needle) in [
            ("[retrofit]\nlayers = 3\n", "layers = 3"),
            ("[[attachment]]\nindex = 9\n", "above 7"),
            (
                "[[attachment]]\nindex = 1\nrule = \"median\"\n",
                "unknown rule",
            ),
            ("[retrofit]\nlayer_mix = \"gamma\"\n", "unknown layer_mix"),
            (
                "[retrofit]\nlayer_mix = \"curve\"\n",
                "needs layer_mix_curve",
            ),
            (
                "[retrofit]\nlayer_mix_curve = \"vec3 dmsaa_curve(vec3 x) { return x; }\"\n",
                "only with layer_mix = \"curve\"",
            ),
            ("[retrofit]\nsampels = 4\n", "not valid"),
            ("[lighting]\npass = 0\n", "counts from 1"),
            ("[projection]\nmatrix = [1.0, 0.0]\n", "16 numbers"),
            (
                "[[attachment]]\nindex = 1\nclear = [0.0, 1.0]\n",
                "clear needs 4 numbers",
            ),
        ] {
            let e = Profile::parse(text, "p.toml").expect_err(text).to_string();
            assert!(e.contains(needle), "{text:?}: {e}");
            assert!(!e.contains('\n'), "{e}");
        }
    }
}

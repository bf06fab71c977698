//! What the plan reads: from the scene ([`SceneNeeds`], computed once) and
//! from the context ([`PlanContext`]).

use crate::gbuffer::{DriverMemory, GBufferLayout};
use crate::gl::{Capabilities, Format};
use crate::scene::{AlphaMode, Background, Scene};

/// F0 of a dielectric, as `geometry.frag` writes it for metallic 0.
const DIELECTRIC_F0: f32 = 0.04;

/// What the plan reads from a scene, computed once (the renderer keeps it
/// for [`Renderer::set_options`](crate::renderer::Renderer::set_options)).
#[derive(Clone, Debug, PartialEq)]
pub struct SceneNeeds {
    /// The scene's name.
    pub name: String,
    /// Materials drawn into the G-buffer that emit light.
    pub emitters: Vec<String>,
    /// What those materials write into the specular attachment.
    pub specular: SpecularResponse,
    /// Objects drawn by the forward transparent pass (alpha-blended).
    pub transparent_objects: usize,
    /// The largest view-space coordinate (|x|, |y| or |z|) of the scene's
    /// bounds as its camera sees them; `None` for an empty or non-finite scene.
    pub max_coordinate: Option<f64>,
    /// The smallest detail that must stay apart: 1/1000 of the bounds' radius
    /// (as in the renderer's precision check).
    pub detail: Option<f64>,
    /// The camera's vertical field of view, radians.
    pub fov_y: f64,
    /// Whether the background shows anything (it is not plain black).
    pub background_visible: bool,
}

/// The value the G-buffer's materials write into the specular attachment.
#[derive(Clone, Debug, PartialEq)]
pub enum SpecularResponse {
    /// Every material writes this (F0 rgb, metallic), in full precision.
    Uniform([f32; 4]),
    /// The materials differ; why, in words.
    Varying(String),
}

/// What `geometry.frag` writes into the specular attachment for a material,
/// when it is one value (no base-colour texture feeds a metallic F0).
fn specular_of(m: &crate::scene::Material) -> std::result::Result<[f32; 4], String> {
    let metallic = m.metallic.clamp(0.0, 1.0);
    if metallic == 0.0 {
        return Ok([DIELECTRIC_F0, DIELECTRIC_F0, DIELECTRIC_F0, 0.0]);
    }
    if m.base_color_texture.is_some() {
        return Err(format!(
            "material `{}` is metallic with a base-colour texture: its F0 varies per texel",
            m.name
        ));
    }
    // mix(vec3(0.04), base.rgb, metallic), as the shader computes it.
    let f0 = |c: f32| DIELECTRIC_F0 * (1.0 - metallic) + c * metallic;
    Ok([
        f0(m.base_color[0]),
        f0(m.base_color[1]),
        f0(m.base_color[2]),
        metallic,
    ])
}

impl SceneNeeds {
    /// Read `scene`.
    pub fn of(scene: &Scene) -> Self {
        let mut emitters: Vec<String> = Vec::new();
        let mut specular: Option<(String, [f32; 4])> = None;
        let mut varying: Option<String> = None;
        let mut transparent_objects = 0;
        for object in &scene.objects {
            let Some(m) = scene.materials.get(object.material) else {
                continue;
            };
            if m.alpha_mode == AlphaMode::Blend {
                transparent_objects += 1;
                continue;
            }
            if m.is_emissive() && !emitters.contains(&m.name) {
                emitters.push(m.name.clone());
            }
            if varying.is_some() {
                continue;
            }
            match (specular_of(m), &specular) {
                (Err(why), _) => varying = Some(why),
                (Ok(v), None) => specular = Some((m.name.clone(), v)),
                (Ok(v), Some((first, w))) if v != *w => {
                    varying = Some(format!(
                        "materials `{first}` and `{}` differ (F0 {:.3}, metallic {:.2} against F0 {:.3}, metallic {:.2})",
                        m.name, w[0], w[3], v[0], v[3]
                    ));
                }
                (Ok(_), Some(_)) => {}
            }
        }
        let specular = match (varying, specular) {
            (Some(why), _) => SpecularResponse::Varying(why),
            (None, Some((_, v))) => SpecularResponse::Uniform(v),
            // Nothing is drawn into the G-buffer: any constant will do.
            (None, None) => {
                SpecularResponse::Uniform([DIELECTRIC_F0, DIELECTRIC_F0, DIELECTRIC_F0, 0.0])
            }
        };
        let (max_coordinate, detail) = if scene.bounds.is_empty() {
            (None, None)
        } else {
            let view = scene.camera.view.as_dmat4();
            let max = scene
                .bounds
                .corners()
                .iter()
                .map(|c| view.transform_point3(c.as_dvec3()).abs().max_element())
                .fold(0.0f64, f64::max);
            let radius = (scene.bounds.max.as_dvec3() - scene.bounds.min.as_dvec3()).length() * 0.5;
            let detail = radius * 1e-3;
            let ok = max.is_finite() && detail.is_finite() && detail > 0.0;
            (ok.then_some(max), ok.then_some(detail))
        };
        SceneNeeds {
            name: scene.name.clone(),
            emitters,
            specular,
            transparent_objects,
            max_coordinate,
            detail,
            fov_y: f64::from(scene.camera.fov_y),
            background_visible: scene.background != Background::Black,
        }
    }
}

/// What the plan needs to know about the context.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanContext {
    /// Sample counts a multisampled texture of every format the plan may
    /// pick really gets, ascending (llvmpipe: `[4]`).
    pub sample_counts: Vec<u32>,
    /// Free video memory, where the driver reports it.
    pub driver_memory: Option<DriverMemory>,
}

impl PlanContext {
    /// Query the current context for a plan starting from `layout`: the
    /// sample counts every one of its formats (and FP16 positions) gets.
    pub fn query(gl: &glow::Context, layout: &GBufferLayout) -> Self {
        let mut formats: Vec<Format> = layout.colors.iter().map(|a| a.format).collect();
        formats.push(layout.depth);
        formats.push(Format::Rgba16f);
        formats.dedup();
        let mut counts: Option<Vec<u32>> = None;
        let mut seen: Vec<Format> = Vec::new();
        for f in formats {
            if seen.contains(&f) {
                continue;
            }
            seen.push(f);
            let offered = Capabilities::sample_counts_for(gl, f);
            counts = Some(match counts {
                None => offered,
                Some(c) => c.into_iter().filter(|n| offered.contains(n)).collect(),
            });
        }
        PlanContext {
            sample_counts: counts.unwrap_or_default(),
            driver_memory: DriverMemory::query(gl),
        }
    }
}

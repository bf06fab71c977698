//! Materials: glTF metallic-roughness materials (with
//! `KHR_materials_emissive_strength`, alpha modes and double-sidedness) as
//! the scene's, each converted once with non-finite factors replaced by the
//! defaults; their base colour and emissive textures, each image decoded
//! once; and the texture-coordinate set a material's textures use.

use std::collections::HashMap;
use std::path::Path;

use super::super::{AlphaMode, Material, TextureData, Warnings};
use super::images::decode_image;

/// The scene's materials and textures, converted as the walk first meets them.
#[derive(Default)]
pub(super) struct Materials {
    materials: Vec<Material>,
    /// glTF material index (None: the default material) → ours.
    material_map: HashMap<Option<usize>, usize>,
    textures: Vec<TextureData>,
    /// glTF image index → ours (None: it failed to load; warned once).
    texture_map: HashMap<usize, Option<usize>>,
}

impl Materials {
    /// Our index of glTF material `m` of `document`, converting it (and
    /// decoding its textures from `buffers` or files under `base`) the
    /// first time.
    pub(super) fn material(
        &mut self,
        document: &gltf::Document,
        m: gltf::Material,
        buffers: &[Vec<u8>],
        base: Option<&Path>,
        warnings: &mut Warnings,
    ) -> usize {
        if let Some(&i) = self.material_map.get(&m.index()) {
            return i;
        }
        let pbr = m.pbr_metallic_roughness();
        let finite_or = |v: f32, d: f32| if v.is_finite() { v } else { d };
        let base_color = pbr.base_color_factor().map(|c| finite_or(c, 1.0));
        let strength = m.emissive_strength().unwrap_or(1.0);
        let strength = if strength.is_finite() && strength >= 0.0 {
            strength
        } else {
            1.0
        };
        let emissive = m
            .emissive_factor()
            .map(|e| finite_or(e, 0.0).max(0.0) * strength);
        let base_color_texture = pbr
            .base_color_texture()
            .and_then(|info| self.texture(document, &info.texture(), buffers, base, warnings));
        let emissive_texture = m
            .emissive_texture()
            .and_then(|info| self.texture(document, &info.texture(), buffers, base, warnings));
        let material = Material {
            name: m.name().unwrap_or_default().to_string(),
            base_color,
            base_color_texture,
            metallic: finite_or(pbr.metallic_factor(), 1.0).clamp(0.0, 1.0),
            roughness: finite_or(pbr.roughness_factor(), 1.0).clamp(0.0, 1.0),
            emissive,
            emissive_texture,
            alpha_mode: match m.alpha_mode() {
                gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
                gltf::material::AlphaMode::Mask => AlphaMode::Mask,
                gltf::material::AlphaMode::Blend => AlphaMode::Blend,
            },
            alpha_cutoff: finite_or(m.alpha_cutoff().unwrap_or(0.5), 0.5),
            double_sided: m.double_sided(),
        };
        self.materials.push(material);
        let i = self.materials.len() - 1;
        self.material_map.insert(m.index(), i);
        i
    }

    /// Decodes a texture's image once; `None` (with a warning) when it cannot.
    fn texture(
        &mut self,
        document: &gltf::Document,
        texture: &gltf::Texture,
        buffers: &[Vec<u8>],
        base: Option<&Path>,
        warnings: &mut Warnings,
    ) -> Option<usize> {
        let index = texture.source().index();
        if let Some(&known) = self.texture_map.get(&index) {
            return known;
        }
        let result = match decode_image(document, index, buffers, base) {
            Ok(t) => {
                self.textures.push(t);
                Some(self.textures.len() - 1)
            }
            Err(e) => {
                warnings.push(format!(
                    "texture image {index}: {e}; the material's factor is used alone"
                ));
                None
            }
        };
        self.texture_map.insert(index, result);
        result
    }

    /// The scene's materials and textures, in the order first met.
    pub(super) fn into_parts(self) -> (Vec<Material>, Vec<TextureData>) {
        (self.materials, self.textures)
    }
}

/// The texture-coordinate set the material's textures use.
pub(super) fn uv_set(m: &gltf::Material, warnings: &mut Warnings) -> u32 {
    let base = m
        .pbr_metallic_roughness()
        .base_color_texture()
        .map(|t| t.tex_coord());
    let emissive = m.emissive_texture().map(|t| t.tex_coord());
    match (base, emissive) {
        (Some(b), Some(e)) if b != e => {
            warnings.push(format!(
                "material {}: base colour and emissive textures use different coordinate sets; TEXCOORD_{b} is used for both",
                m.index().map_or("default".into(), |i| i.to_string())
            ));
            b
        }
        (Some(b), _) => b,
        (None, Some(e)) => e,
        (None, None) => 0,
    }
}

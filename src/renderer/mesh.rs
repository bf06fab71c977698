//! The scene on the GPU: one vertex array per object, the material textures,
//! and the draw lists (G-buffer objects and forward transparent objects).

use crate::gl::destroy_object;
use crate::gl::{
    Buffer, Format, GlObject, Handle, Made, Program, Texture2d, VertexArray, check_error,
};
use crate::scene::{AlphaMode, Material, Object, Scene};
use crate::{Error, Result};
use glam::{DMat4, DVec3};
use glow::HasContext;
use std::cell::Cell;

/// Texture unit of the base colour texture in the model shaders.
pub(crate) const BASE_TEXTURE_UNIT: u32 = 0;
/// Texture unit of the emissive texture in the model shaders.
pub(crate) const EMISSIVE_TEXTURE_UNIT: u32 = 1;

/// Where a linked program reads the vertex attributes (GLSL 1.50 has no
/// `layout(location)` for inputs, so they are queried after linking).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct AttribLocations {
    position: Option<u32>,
    normal: Option<u32>,
    uv: Option<u32>,
}

impl AttribLocations {
    /// The locations `program` gave `a_position`, `a_normal` and `a_uv`.
    pub(crate) fn of(gl: &glow::Context, program: &Program) -> Self {
        unsafe {
            AttribLocations {
                position: gl.get_attrib_location(program.raw(), "a_position"),
                normal: gl.get_attrib_location(program.raw(), "a_normal"),
                uv: gl.get_attrib_location(program.raw(), "a_uv"),
            }
        }
    }
}

/// One object's vertex data.
#[derive(Debug)]
pub(crate) struct GpuMesh {
    vao: VertexArray,
    positions: Buffer,
    normals: Buffer,
    uvs: Buffer,
    indices: Buffer,
    index_count: i32,
    /// The locations the vertex array is set up for.
    configured: Cell<Option<AttribLocations>>,
}

impl GpuMesh {
    fn new(gl: &glow::Context, object: &Object) -> Result<Self> {
        let label = |what: &str| format!("{} {what}", object.name);
        let (positions, normals, uvs, indices, vao) = Made::build(gl, |made| {
            let vertex_data = |what: &str, target, data: &[u8]| {
                Buffer::with_data(gl, &label(what), target, data, glow::STATIC_DRAW)
            };
            let positions = made.keep(vertex_data(
                "positions",
                glow::ARRAY_BUFFER,
                bytemuck::cast_slice(&object.positions),
            )?);
            let normals = made.keep(vertex_data(
                "normals",
                glow::ARRAY_BUFFER,
                bytemuck::cast_slice(&object.normals),
            )?);
            let uvs = made.keep(vertex_data(
                "uvs",
                glow::ARRAY_BUFFER,
                bytemuck::cast_slice(&object.uvs),
            )?);
            let indices = made.keep(vertex_data(
                "indices",
                glow::ELEMENT_ARRAY_BUFFER,
                bytemuck::cast_slice(&object.indices),
            )?);
            let vao = made.keep(VertexArray::new(gl, &label("vertex array"))?);
            Ok::<_, crate::Error>((positions, normals, uvs, indices, vao))
        })?;
        unsafe {
            vao.bind(gl);
            gl.bind_buffer(glow::ELEMENT_ARRAY_BUFFER, Some(indices.raw()));
            gl.bind_vertex_array(None);
            gl.bind_buffer(glow::ELEMENT_ARRAY_BUFFER, None);
        }
        Ok(GpuMesh {
            vao,
            positions,
            normals,
            uvs,
            indices,
            index_count: object.indices.len() as i32,
            configured: Cell::new(None),
        })
    }

    /// Bind the vertex array with the attributes where `locations` wants
    /// them (re-specified only when they change), and draw.
    pub(crate) fn draw(&self, gl: &glow::Context, locations: AttribLocations) {
        self.vao.bind(gl);
        if self.configured.get() != Some(locations) {
            unsafe {
                if let Some(old) = self.configured.get() {
                    for loc in [old.position, old.normal, old.uv].into_iter().flatten() {
                        gl.disable_vertex_attrib_array(loc);
                    }
                }
                let streams = [
                    (locations.position, &self.positions, 3),
                    (locations.normal, &self.normals, 3),
                    (locations.uv, &self.uvs, 2),
                ];
                for (loc, buffer, size) in streams {
                    if let Some(loc) = loc {
                        gl.bind_buffer(glow::ARRAY_BUFFER, Some(buffer.raw()));
                        gl.vertex_attrib_pointer_f32(loc, size, glow::FLOAT, false, 0, 0);
                        gl.enable_vertex_attrib_array(loc);
                    }
                }
                gl.bind_buffer(glow::ARRAY_BUFFER, None);
            }
            self.configured.set(Some(locations));
        }
        unsafe {
            gl.draw_elements(glow::TRIANGLES, self.index_count, glow::UNSIGNED_INT, 0);
        }
    }
}

impl GlObject for GpuMesh {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.vao.handles(out);
        self.positions.handles(out);
        self.normals.handles(out);
        self.uvs.handles(out);
        self.indices.handles(out);
    }
}

/// One drawable: its mesh, model matrix and material.
#[derive(Clone, Debug)]
pub(crate) struct DrawItem {
    /// Index into [`GpuScene::meshes`].
    pub(crate) mesh: usize,
    /// Model to world, in double precision (far scenes sit 200 km away).
    pub(crate) model: DMat4,
    /// The material.
    pub(crate) material: Material,
    /// World-space centre of its bounds (for sorting transparent objects).
    pub(crate) center: DVec3,
    /// The object's [`Object::antialias`] flag (selective anti-aliasing).
    pub(crate) antialias: bool,
}

impl DrawItem {
    /// Model-view and its inverse transpose, as `f32` column arrays.
    pub(crate) fn matrices(&self, view: &DMat4) -> ([f32; 16], [f32; 16]) {
        let model_view = *view * self.model;
        let normal = model_view.inverse().transpose();
        let normal = if normal.is_finite() {
            normal
        } else {
            DMat4::IDENTITY
        };
        (
            model_view.as_mat4().to_cols_array(),
            normal.as_mat4().to_cols_array(),
        )
    }
}

/// The scene's GPU resources and draw lists.
#[derive(Debug)]
pub(crate) struct GpuScene {
    /// One mesh per drawable object.
    pub(crate) meshes: Vec<GpuMesh>,
    /// Material textures, indexed like [`Scene::textures`].
    textures: Vec<Texture2d>,
    /// A 1×1 white texel bound where a material has no texture.
    white: Texture2d,
    /// Opaque and alpha-tested objects, drawn into the G-buffer.
    pub(crate) gbuffer_items: Vec<DrawItem>,
    /// Alpha-blended objects, drawn forward after lighting.
    pub(crate) transparent_items: Vec<DrawItem>,
}

fn upload_texture(
    gl: &glow::Context,
    index: usize,
    data: &crate::scene::TextureData,
) -> Result<Texture2d> {
    let expected = data.width as usize * data.height as usize * 4;
    if data.rgba8.len() != expected {
        return Err(Error::invalid(format!(
            "scene texture {index}: {} bytes for {}x{} RGBA8 (expected {expected})",
            data.rgba8.len(),
            data.width,
            data.height
        )));
    }
    let format = if data.srgb {
        Format::Srgb8Alpha8
    } else {
        Format::Rgba8
    };
    Made::build(gl, |made| {
        let texture = made.keep(Texture2d::with_data(
            gl,
            &format!("scene texture {index}"),
            format,
            data.width,
            data.height,
            Some(&data.rgba8),
        )?);
        unsafe {
            gl.bind_texture(glow::TEXTURE_2D, Some(texture.raw()));
            gl.generate_mipmap(glow::TEXTURE_2D);
            gl.tex_parameter_i32(
                glow::TEXTURE_2D,
                glow::TEXTURE_MIN_FILTER,
                glow::LINEAR_MIPMAP_LINEAR as i32,
            );
            gl.tex_parameter_i32(
                glow::TEXTURE_2D,
                glow::TEXTURE_MAG_FILTER,
                glow::LINEAR as i32,
            );
            gl.tex_parameter_i32(glow::TEXTURE_2D, glow::TEXTURE_WRAP_S, glow::REPEAT as i32);
            gl.tex_parameter_i32(glow::TEXTURE_2D, glow::TEXTURE_WRAP_T, glow::REPEAT as i32);
            gl.bind_texture(glow::TEXTURE_2D, None);
        }
        check_error(gl, &format!("building mipmaps of scene texture {index}"))?;
        Ok(texture)
    })
}

impl GpuScene {
    /// Upload every object with triangles and every texture.
    pub(crate) fn new(gl: &glow::Context, scene: &Scene) -> Result<Self> {
        Made::build(gl, |made| {
            let white = made.keep(Texture2d::with_data(
                gl,
                "white texel",
                Format::Rgba8,
                1,
                1,
                Some(&[255; 4]),
            )?);
            let mut gpu = GpuScene {
                meshes: Vec::new(),
                textures: Vec::new(),
                white,
                gbuffer_items: Vec::new(),
                transparent_items: Vec::new(),
            };
            gpu.upload(gl, scene, made)?;
            Ok(gpu)
        })
    }

    /// Upload into `self`, every object through `made` (freed by it on failure).
    fn upload(&mut self, gl: &glow::Context, scene: &Scene, made: &mut Made) -> Result<()> {
        for (index, data) in scene.textures.iter().enumerate() {
            self.textures
                .push(made.keep(upload_texture(gl, index, data)?));
        }
        for object in &scene.objects {
            if object.indices.len() < 3 || object.positions.is_empty() {
                continue;
            }
            let n = object.positions.len();
            if object.normals.len() != n || object.uvs.len() != n {
                return Err(Error::invalid(format!(
                    "object `{}`: {n} positions but {} normals and {} texture coordinates",
                    object.name,
                    object.normals.len(),
                    object.uvs.len()
                )));
            }
            let mesh = self.meshes.len();
            self.meshes.push(made.keep(GpuMesh::new(gl, object)?));
            let material = scene.material_of(object);
            let item = DrawItem {
                mesh,
                model: object.transform.as_dmat4(),
                center: object.world_bounds().center().as_dvec3(),
                antialias: object.antialias,
                material,
            };
            if item.material.alpha_mode == AlphaMode::Blend {
                self.transparent_items.push(item);
            } else {
                self.gbuffer_items.push(item);
            }
        }
        Ok(())
    }

    /// Set a model program's material uniforms and bind its textures (the
    /// white texel where the material has none). The program must be bound.
    pub(crate) fn bind_material(&self, gl: &glow::Context, program: &Program, material: &Material) {
        let texture = |index: Option<usize>| {
            index
                .and_then(|i| self.textures.get(i))
                .unwrap_or(&self.white)
        };
        unsafe {
            gl.active_texture(glow::TEXTURE0 + BASE_TEXTURE_UNIT);
            gl.bind_texture(
                glow::TEXTURE_2D,
                Some(texture(material.base_color_texture).raw()),
            );
            gl.active_texture(glow::TEXTURE0 + EMISSIVE_TEXTURE_UNIT);
            gl.bind_texture(
                glow::TEXTURE_2D,
                Some(texture(material.emissive_texture).raw()),
            );
        }
        program.set_vec4(gl, "u_base_color", material.base_color);
        program.set_f32(gl, "u_metallic", material.metallic);
        program.set_f32(gl, "u_roughness", material.roughness);
        program.set_vec3(gl, "u_emissive", material.emissive);
        let cutoff = match material.alpha_mode {
            AlphaMode::Mask => material.alpha_cutoff,
            AlphaMode::Opaque | AlphaMode::Blend => -1.0,
        };
        program.set_f32(gl, "u_alpha_cutoff", cutoff);
        program.set_i32(gl, "u_double_sided", material.double_sided as i32);
    }

    /// Free every buffer, vertex array and texture.
    pub(crate) fn destroy(self, gl: &glow::Context) {
        destroy_object(gl, self);
    }
}

impl GlObject for GpuScene {
    fn handles(&self, out: &mut Vec<Handle>) {
        self.meshes.handles(out);
        self.textures.handles(out);
        self.white.handles(out);
    }
}

/// Set face culling for a material: back faces are culled unless it is double-sided.
pub(crate) fn set_culling(gl: &glow::Context, material: &Material) {
    unsafe {
        if material.double_sided {
            gl.disable(glow::CULL_FACE);
        } else {
            gl.enable(glow::CULL_FACE);
            gl.cull_face(glow::BACK);
            gl.front_face(glow::CCW);
        }
    }
}

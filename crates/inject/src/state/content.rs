//! After the first resolve of a retrofit, the G-buffer's colour
//! attachments read back: where every one is uniform (black included), a
//! warning, since the frame will show nothing of the scene. It catches a
//! resolve of a twin the program never cleared or drew (a `glClearBuffer*`
//! made through another framebuffer sharing the G-buffer's textures, a
//! draw by a path the library does not follow). The reads are made inside
//! [`Context::checked`], so `--check` sees that they change nothing.

use super::context::Context;
use super::run::say_once;
use deferred_msaa_capi as capi;
use glow::HasContext;

/// One attachment's texels: `Some(value)` where every texel is that value.
pub(super) fn uniform_value(texels: &[f32]) -> Option<[f32; 4]> {
    let first: [f32; 4] = texels.get(..4)?.try_into().ok()?;
    texels.chunks_exact(4).all(|t| t == first).then_some(first)
}

impl Context {
    /// Read the G-buffer `g`'s colour textures back and warn where every
    /// one is uniform.
    pub(super) fn look_at_resolved(&mut self, g: u32) {
        let Some(f) = self.framebuffers.get(&g) else {
            return;
        };
        let textures = f.colour_textures.clone();
        // A G-buffer of one array's layers: its size is the array's.
        let target = if f.layered {
            glow::TEXTURE_2D_ARRAY
        } else {
            glow::TEXTURE_2D
        };
        let binding = if f.layered {
            glow::TEXTURE_BINDING_2D_ARRAY
        } else {
            glow::TEXTURE_BINDING_2D
        };
        let mut uniform: Vec<(u32, [f32; 4])> = Vec::new();
        let mut read = 0;
        self.checked("the resolved G-buffer read back", |gl| {
            // SAFETY: queries and reads of the current context; every
            // binding and pixel-store value changed is put back.
            unsafe {
                let active_binding = gl.get_parameter_i32(binding) as u32;
                let read_fbo = gl.get_parameter_i32(glow::READ_FRAMEBUFFER_BINDING) as u32;
                let pack_buffer = gl.get_parameter_i32(glow::PIXEL_PACK_BUFFER_BINDING) as u32;
                let pack: Vec<(u32, i32)> = [
                    glow::PACK_ALIGNMENT,
                    glow::PACK_ROW_LENGTH,
                    glow::PACK_SKIP_ROWS,
                    glow::PACK_SKIP_PIXELS,
                ]
                .iter()
                .map(|&p| (p, gl.get_parameter_i32(p)))
                .collect();
                let fbo = std::num::NonZeroU32::new;
                gl.bind_framebuffer(glow::READ_FRAMEBUFFER, fbo(g).map(glow::NativeFramebuffer));
                let read_buffer = gl.get_parameter_i32(glow::READ_BUFFER) as u32;
                gl.bind_buffer(glow::PIXEL_PACK_BUFFER, None);
                gl.pixel_store_i32(glow::PACK_ALIGNMENT, 4);
                gl.pixel_store_i32(glow::PACK_ROW_LENGTH, 0);
                gl.pixel_store_i32(glow::PACK_SKIP_ROWS, 0);
                gl.pixel_store_i32(glow::PACK_SKIP_PIXELS, 0);
                for &(k, texture) in &textures {
                    let attachment = glow::COLOR_ATTACHMENT0 + k;
                    let component = gl.get_framebuffer_attachment_parameter_i32(
                        glow::READ_FRAMEBUFFER,
                        attachment,
                        glow::FRAMEBUFFER_ATTACHMENT_COMPONENT_TYPE,
                    ) as u32;
                    if component == glow::INT || component == glow::UNSIGNED_INT {
                        continue;
                    }
                    gl.bind_texture(target, fbo(texture).map(glow::NativeTexture));
                    let w = gl.get_tex_level_parameter_i32(target, 0, glow::TEXTURE_WIDTH);
                    let h = gl.get_tex_level_parameter_i32(target, 0, glow::TEXTURE_HEIGHT);
                    if w <= 0 || h <= 0 {
                        continue;
                    }
                    let mut texels = vec![0f32; w as usize * h as usize * 4];
                    gl.read_buffer(attachment);
                    gl.read_pixels(
                        0,
                        0,
                        w,
                        h,
                        glow::RGBA,
                        glow::FLOAT,
                        glow::PixelPackData::Slice(Some(bytemuck_f32(&mut texels))),
                    );
                    read += 1;
                    if let Some(v) = uniform_value(&texels) {
                        uniform.push((k, v));
                    }
                }
                gl.read_buffer(read_buffer);
                gl.bind_texture(target, fbo(active_binding).map(glow::NativeTexture));
                for (p, v) in pack {
                    gl.pixel_store_i32(p, v);
                }
                gl.bind_buffer(
                    glow::PIXEL_PACK_BUFFER,
                    fbo(pack_buffer).map(glow::NativeBuffer),
                );
                gl.bind_framebuffer(
                    glow::READ_FRAMEBUFFER,
                    fbo(read_fbo).map(glow::NativeFramebuffer),
                );
            }
            capi::DmsaaStatus::Ok
        });
        if read == 0 || uniform.len() < read {
            return;
        }
        let black = uniform.iter().all(|(_, v)| *v == [0.0; 4]);
        let values: Vec<String> = uniform.iter().map(|(k, v)| format!("{k}: {v:?}")).collect();
        say_once(
            "warning-uniform",
            &format!(
                "warning: after the first resolve, every colour attachment of framebuffer {g} is {} ({}): the \
                 frame shows nothing of the scene. The retrofit's framebuffer stands in for the G-buffer only \
                 where the G-buffer is bound: a glClearBuffer* or a draw made through another framebuffer that \
                 shares its textures (a glClear there is replayed), or a call the library does not follow, \
                 never reaches it",
                if black { "black" } else { "uniform" },
                values.join(", ")
            ),
        );
    }
}

/// The bytes of `v`, for `glReadPixels`.
fn bytemuck_f32(v: &mut [f32]) -> &mut [u8] {
    // SAFETY: any f32 slice is a valid byte slice of four times its length,
    // and every byte pattern is a valid f32.
    unsafe { std::slice::from_raw_parts_mut(v.as_mut_ptr().cast::<u8>(), std::mem::size_of_val(v)) }
}

#[cfg(test)]
mod tests {
    use super::uniform_value;

    #[test]
    fn uniform_means_every_texel_equal() {
        assert_eq!(uniform_value(&[0.0; 8]), Some([0.0; 4]));
        assert_eq!(
            uniform_value(&[1.0, 2.0, 3.0, 4.0, 1.0, 2.0, 3.0, 4.0]),
            Some([1.0, 2.0, 3.0, 4.0])
        );
        assert_eq!(
            uniform_value(&[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5, 0.0]),
            None
        );
        assert_eq!(uniform_value(&[]), None);
    }
}

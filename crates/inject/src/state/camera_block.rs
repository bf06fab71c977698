//! The camera in a uniform block, as engines keep it (std140, a
//! projection and a view at fixed offsets, written with `glBufferSubData`
//! each frame): where a profile names the block, or, with no projection
//! uniform and no profile naming one, where the writes showed it (one
//! perspective projection written into a buffer bound at one binding
//! point, a rigid view beside it: `crate::camera::block_camera`), read
//! back at each resolve.

use super::context::Context;
use super::run::{say_once, settings};
use crate::profile::CameraBlock;
use deferred_msaa_capi as capi;
use glow::HasContext;

impl Context {
    /// The camera block the resolve reads: the profile's, else the one the
    /// writes showed.
    pub(super) fn camera_block(&self) -> Option<CameraBlock> {
        settings()
            .profile
            .as_ref()
            .and_then(|p| p.camera_block())
            .or(self.found_block)
    }

    /// A uniform-buffer binding point bound (`size` 0: the whole buffer).
    pub(super) fn uniform_buffer_bound(
        &mut self,
        index: u32,
        buffer: u32,
        offset: isize,
        size: isize,
    ) {
        self.uniform_bindings
            .insert(index, (buffer, offset as i64, size as i64));
    }

    /// Bytes written at `offset` into uniform buffer `buffer`: a camera in
    /// them is remembered, until a retrofit is made (`--learn` all along).
    pub(super) fn uniform_buffer_written(&mut self, buffer: u32, offset: isize, bytes: &[u8]) {
        if buffer == 0 || offset < 0 || (self.retrofit.is_some() && !self.learning()) {
            return;
        }
        let kinds = self.block_matrices.entry(buffer).or_default();
        for (at, kind) in crate::camera::block_matrices(bytes, offset as usize) {
            match kind {
                Some(k) => kinds.insert(at, k),
                None => kinds.remove(&at),
            };
        }
    }

    /// The bindings whose buffer holds a camera seen written, as camera
    /// blocks (offsets from the binding's start), in binding order.
    pub(crate) fn seen_camera_blocks(&self) -> Vec<CameraBlock> {
        let mut found: Vec<CameraBlock> = self
            .uniform_bindings
            .iter()
            .filter_map(|(&binding, &(buffer, start, size))| {
                let (projection, view) =
                    crate::camera::block_camera(self.block_matrices.get(&buffer)?)?;
                let inside = |o: u32| {
                    let o = i64::from(o);
                    o >= start && (size == 0 || o + 64 <= start + size)
                };
                inside(projection).then(|| CameraBlock {
                    binding,
                    offset: (i64::from(projection) - start) as u32,
                    view_offset: view
                        .filter(|&v| inside(v))
                        .map(|v| (i64::from(v) - start) as u32),
                })
            })
            .collect();
        found.sort_by_key(|b| b.binding);
        found
    }

    /// With no projection uniform and no block named: the camera block the
    /// writes showed, where exactly one binding point holds one (`Ok(None)`
    /// where none does). Where several do, one line says so and names the
    /// way out, and `Err(())`: the program is left alone.
    pub(super) fn find_camera_block(&mut self, g: u32) -> Result<Option<CameraBlock>, ()> {
        let found = self.seen_camera_blocks();
        match found.as_slice() {
            [one] => {
                self.found_block = Some(*one);
                Ok(Some(*one))
            }
            [] => Ok(None),
            several => {
                let bindings: Vec<String> = several.iter().map(|b| b.binding.to_string()).collect();
                say_once(
                    "camera-blocks",
                    &format!(
                        "found the G-buffer (framebuffer {g}); uniform blocks at bindings [{}] each hold a \
                         perspective projection (a shadow or reflection camera beside the view's?): leaving the \
                         program untouched (a profile names the camera's: [projection] block_binding, offset)",
                        bindings.join(", ")
                    ),
                );
                Err(())
            }
        }
    }

    /// The matrices block `block` holds now (projection, view): the buffer
    /// bound at its binding point read back at its offsets, inside the
    /// check's brackets; `None` where no buffer is bound or it is too small.
    fn camera_block_matrices(
        &mut self,
        block: CameraBlock,
    ) -> (Option<[f32; 16]>, Option<[f32; 16]>) {
        let mut read: (Option<[f32; 16]>, Option<[f32; 16]>) = (None, None);
        self.checked("the camera read from its uniform block", |gl| {
            // SAFETY: queries and a buffer read of the current context;
            // the copy-read binding is put back.
            unsafe {
                let buffer = gl
                    .get_parameter_indexed_i32(glow::UNIFORM_BUFFER_BINDING, block.binding)
                    as u32;
                let Some(name) = std::num::NonZeroU32::new(buffer) else {
                    return capi::DmsaaStatus::Ok;
                };
                let start = gl
                    .get_parameter_indexed_i32(glow::UNIFORM_BUFFER_START, block.binding)
                    .max(0);
                let saved = gl.get_parameter_i32(glow::COPY_READ_BUFFER_BINDING) as u32;
                gl.bind_buffer(glow::COPY_READ_BUFFER, Some(glow::NativeBuffer(name)));
                let size = gl.get_buffer_parameter_i32(glow::COPY_READ_BUFFER, glow::BUFFER_SIZE);
                let matrix = |offset: u32| -> Option<[f32; 16]> {
                    let at = start + offset as i32;
                    if at + 64 > size {
                        return None;
                    }
                    let mut bytes = [0u8; 64];
                    gl.get_buffer_sub_data(glow::COPY_READ_BUFFER, at, &mut bytes);
                    crate::camera::matrix_at(&bytes, 0)
                };
                read = (matrix(block.offset), block.view_offset.and_then(matrix));
                gl.bind_buffer(
                    glow::COPY_READ_BUFFER,
                    std::num::NonZeroU32::new(saved).map(glow::NativeBuffer),
                );
            }
            capi::DmsaaStatus::Ok
        });
        read
    }

    /// The camera as the program's uniform block holds it at a resolve, in
    /// place of a uniform's. Where the block holds none now, the last camera
    /// read is kept, said once; where none was ever read, the retrofit is
    /// off from now on, said once (this frame's geometry, drawn into the
    /// retrofit's framebuffer, is lost; the next frames are the program's
    /// own, not frames never resolved). Whether there is a camera.
    pub(super) fn read_camera_block(&mut self, block: CameraBlock) -> bool {
        match self.camera_block_matrices(block) {
            (Some(projection), view) => {
                self.projection = Some(projection);
                if view.is_some() {
                    self.view = view;
                }
                true
            }
            (None, _) => {
                let known = self.projection.is_some();
                say_once(
                    "camera-block",
                    &format!(
                        "the camera block (uniform-buffer binding {}, projection at byte {}) holds no matrix there: \
                         no buffer bound, or one too small; {}",
                        block.binding,
                        block.offset,
                        if known {
                            "the frame is resolved with the last camera read"
                        } else {
                            "the retrofit is off for the rest of the run (check [projection] block_binding and offset)"
                        }
                    ),
                );
                if !known {
                    self.give_up();
                }
                known
            }
        }
    }
}

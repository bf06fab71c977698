//! The GPU memory of [`AaMode::Sparse`](crate::renderer::AaMode::Sparse): the
//! multisampled depth-stencil of the pre-pass and its framebuffer, the
//! per-pixel heads, the first-block area, the block pool and the two atomic
//! counters (next pool block, overflowed pixels). The layout of heads and
//! blocks is in `sparse.frag`.

use super::options::SparseOptions;
use crate::gl::{
    Attachment, Buffer, Format, Framebuffer, Made, Texture2dMultisample, TextureRef, check_error,
};
use crate::{Error, Result};
use glow::HasContext;

/// Bytes of one block: two `uvec4`s.
pub(crate) const BLOCK_BYTES: u64 = 32;
/// Bytes of one pixel's head: the pool list's first index and the flags.
pub(crate) const HEAD_BYTES: u64 = 8;
/// Bytes of the atomic counter buffer: next pool block, overflowed pixels.
pub(crate) const COUNTER_BYTES: usize = 8;

/// Shader storage binding of the heads.
pub(crate) const HEADS_BINDING: u32 = 0;
/// Shader storage binding of the first-block area.
pub(crate) const FIRST_BINDING: u32 = 1;
/// Shader storage binding of the pool.
pub(crate) const POOL_BINDING: u32 = 2;
/// Atomic counter buffer binding.
pub(crate) const COUNTER_BINDING: u32 = 0;

/// The depth-stencil format of the pre-pass for a layout whose depth is
/// `depth`: 32-bit float depth when the layout has float depth (reversed-Z
/// keeps its precision), else 24-bit; both with the 8-bit stencil that
/// keeps blocks unique.
pub(crate) fn prepass_format(depth: Format) -> Format {
    match depth {
        Format::Depth32f | Format::Depth32fStencil8 => Format::Depth32fStencil8,
        _ => Format::Depth24Stencil8,
    }
}

/// Everything sized by the frame and the pool.
#[derive(Debug)]
pub(crate) struct SparseTargets {
    /// The pre-pass depth and stencil, multisampled.
    pub(crate) depth: Texture2dMultisample,
    /// A framebuffer with only `depth` attached (no colour): the pre-pass
    /// and the G-buffer pass draw here.
    pub(crate) fbo: Framebuffer,
    /// Two `uint`s per pixel.
    pub(crate) heads: Buffer,
    /// One block per pixel.
    pub(crate) first: Buffer,
    /// `pool_capacity` blocks (at least one block of storage).
    pub(crate) pool: Buffer,
    /// Two atomic counters.
    pub(crate) counters: Buffer,
    /// Width in pixels.
    pub(crate) width: u32,
    /// Height in pixels.
    pub(crate) height: u32,
    /// Blocks the pool may hand out.
    pub(crate) pool_capacity: u32,
}

/// What the targets were allocated for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct TargetKey {
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) samples: u32,
    pub(crate) format: Format,
    pub(crate) pool_capacity: u32,
}

impl SparseTargets {
    /// Allocate for `key`. Buffers larger than the context's
    /// `GL_MAX_SHADER_STORAGE_BLOCK_SIZE` are refused with a one-line error
    /// before anything is allocated.
    pub(crate) fn new(gl: &glow::Context, key: TargetKey) -> Result<Self> {
        let pixels = u64::from(key.width) * u64::from(key.height);
        let pool_storage = u64::from(key.pool_capacity.max(1));
        let limit = unsafe { gl.get_parameter_i64(glow::MAX_SHADER_STORAGE_BLOCK_SIZE) };
        let _ = check_error(gl, "querying GL_MAX_SHADER_STORAGE_BLOCK_SIZE");
        let sizes = [
            ("per-pixel heads", pixels * HEAD_BYTES),
            ("first-block area", pixels * BLOCK_BYTES),
            ("block pool", pool_storage * BLOCK_BYTES),
        ];
        for (what, bytes) in sizes {
            if limit > 0 && bytes > limit as u64 {
                return Err(Error::invalid(format!(
                    "method `sparse` at {}x{}: its {what} needs {bytes} bytes, over this context's \
                     GL_MAX_SHADER_STORAGE_BLOCK_SIZE of {limit}; use a smaller size or pool",
                    key.width, key.height
                )));
            }
        }
        let size = |bytes: u64| {
            usize::try_from(bytes).map_err(|_| {
                Error::invalid(format!(
                    "method `sparse`: {bytes} bytes do not fit in memory"
                ))
            })
        };
        let (heads_bytes, first_bytes, pool_bytes) =
            (size(sizes[0].1)?, size(sizes[1].1)?, size(sizes[2].1)?);

        Made::build(gl, |made| {
            let depth = made.keep(Texture2dMultisample::new(
                gl,
                "sparse pre-pass depth",
                key.format,
                key.width,
                key.height,
                key.samples,
            )?);
            let fbo = made.keep(Framebuffer::new(
                gl,
                "sparse pre-pass",
                &[(Attachment::DepthStencil, TextureRef::from(&depth))],
                &[],
            )?);
            let storage = |label: &str, bytes| {
                Buffer::with_size(
                    gl,
                    label,
                    glow::SHADER_STORAGE_BUFFER,
                    bytes,
                    glow::DYNAMIC_COPY,
                )
            };
            let heads = made.keep(storage("sparse heads", heads_bytes)?);
            let first = made.keep(storage("sparse first blocks", first_bytes)?);
            let pool = made.keep(storage("sparse block pool", pool_bytes)?);
            let counters = made.keep(Buffer::with_data(
                gl,
                "sparse counters",
                glow::ATOMIC_COUNTER_BUFFER,
                &[0u8; COUNTER_BYTES],
                glow::DYNAMIC_COPY,
            )?);
            Ok(SparseTargets {
                depth,
                fbo,
                heads,
                first,
                pool,
                counters,
                width: key.width,
                height: key.height,
                pool_capacity: key.pool_capacity,
            })
        })
    }

    /// The key these targets match.
    pub(crate) fn key(&self) -> TargetKey {
        TargetKey {
            width: self.width,
            height: self.height,
            samples: self.depth.requested_samples,
            format: self.depth.format,
            pool_capacity: self.pool_capacity,
        }
    }

    /// The real sample count of the pre-pass.
    pub(crate) fn samples(&self) -> u32 {
        self.depth.samples
    }

    /// What is allocated, by part.
    pub(crate) fn memory(&self) -> SparseMemory {
        SparseMemory {
            heads: self.heads.size as u64,
            first_blocks: self.first.size as u64,
            pool: self.pool.size as u64,
            depth: self.depth.bytes(),
            counters: self.counters.size as u64,
        }
    }

    /// Bind the three storage buffers and the counters to their binding points.
    pub(crate) fn bind_buffers(&self, gl: &glow::Context) {
        unsafe {
            gl.bind_buffer_base(
                glow::SHADER_STORAGE_BUFFER,
                HEADS_BINDING,
                Some(self.heads.raw()),
            );
            gl.bind_buffer_base(
                glow::SHADER_STORAGE_BUFFER,
                FIRST_BINDING,
                Some(self.first.raw()),
            );
            gl.bind_buffer_base(
                glow::SHADER_STORAGE_BUFFER,
                POOL_BINDING,
                Some(self.pool.raw()),
            );
            gl.bind_buffer_base(
                glow::ATOMIC_COUNTER_BUFFER,
                COUNTER_BINDING,
                Some(self.counters.raw()),
            );
        }
    }

    /// Unbind what [`SparseTargets::bind_buffers`] bound.
    pub(crate) fn unbind_buffers(gl: &glow::Context) {
        unsafe {
            for binding in [HEADS_BINDING, FIRST_BINDING, POOL_BINDING] {
                gl.bind_buffer_base(glow::SHADER_STORAGE_BUFFER, binding, None);
            }
            gl.bind_buffer_base(glow::ATOMIC_COUNTER_BUFFER, COUNTER_BINDING, None);
        }
    }

    /// Zero both counters (before the G-buffer pass).
    pub(crate) fn reset_counters(&self, gl: &glow::Context) {
        unsafe {
            gl.bind_buffer(glow::ATOMIC_COUNTER_BUFFER, Some(self.counters.raw()));
            gl.buffer_sub_data_u8_slice(glow::ATOMIC_COUNTER_BUFFER, 0, &[0u8; COUNTER_BYTES]);
            gl.bind_buffer(glow::ATOMIC_COUNTER_BUFFER, None);
        }
    }

    /// The counters as the last G-buffer pass left them: blocks asked of
    /// the pool (including those refused), and pixels that overflowed.
    pub(crate) fn read_counters(&self, gl: &glow::Context) -> Result<(u32, u32)> {
        let mut bytes = [0u8; COUNTER_BYTES];
        unsafe {
            gl.memory_barrier(glow::BUFFER_UPDATE_BARRIER_BIT | glow::ATOMIC_COUNTER_BARRIER_BIT);
            gl.bind_buffer(glow::ATOMIC_COUNTER_BUFFER, Some(self.counters.raw()));
            gl.get_buffer_sub_data(glow::ATOMIC_COUNTER_BUFFER, 0, &mut bytes);
            gl.bind_buffer(glow::ATOMIC_COUNTER_BUFFER, None);
        }
        check_error(gl, "reading the sparse G-buffer's counters")?;
        let word =
            |k: usize| u32::from_le_bytes([bytes[k], bytes[k + 1], bytes[k + 2], bytes[k + 3]]);
        Ok((word(0), word(4)))
    }

    /// Every pixel's flags (`SPARSE_*` of `sparse.frag`), bottom row first.
    pub(crate) fn read_flags(&self, gl: &glow::Context) -> Result<Vec<u32>> {
        let mut bytes = vec![0u8; self.heads.size];
        unsafe {
            gl.memory_barrier(glow::BUFFER_UPDATE_BARRIER_BIT);
            gl.bind_buffer(glow::SHADER_STORAGE_BUFFER, Some(self.heads.raw()));
            gl.get_buffer_sub_data(glow::SHADER_STORAGE_BUFFER, 0, &mut bytes);
            gl.bind_buffer(glow::SHADER_STORAGE_BUFFER, None);
        }
        check_error(gl, "reading the sparse G-buffer's heads")?;
        Ok(bytes
            .chunks_exact(HEAD_BYTES as usize)
            .map(|h| u32::from_le_bytes([h[4], h[5], h[6], h[7]]))
            .collect())
    }

    /// Free everything.
    pub(crate) fn destroy(self, gl: &glow::Context) {
        free(
            gl,
            self.depth,
            self.fbo,
            vec![self.heads, self.first, self.pool, self.counters],
        );
    }
}

fn free(gl: &glow::Context, depth: Texture2dMultisample, fbo: Framebuffer, buffers: Vec<Buffer>) {
    for b in buffers {
        b.destroy(gl);
    }
    fbo.destroy(gl);
    depth.destroy(gl);
}

/// The GPU memory [`AaMode::Sparse`](crate::renderer::AaMode::Sparse) allocates, in bytes, by part.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct SparseMemory {
    /// Per-pixel heads: the list's first pool block and the flags (8 bytes a pixel).
    pub heads: u64,
    /// The first-block area: one 32-byte block per pixel.
    pub first_blocks: u64,
    /// The pool: [`SparseOptions::pool_capacity`] 32-byte blocks.
    pub pool: u64,
    /// The multisampled depth-stencil of the pre-pass.
    pub depth: u64,
    /// The two atomic counters.
    pub counters: u64,
}

impl SparseMemory {
    /// What [`AaMode::Sparse`](crate::renderer::AaMode::Sparse) with `options` allocates for a
    /// `width`×`height` frame at `samples` samples with a depth format
    /// `depth` (the layout's; the pre-pass adds stencil), before allocating.
    pub fn planned(
        options: &SparseOptions,
        width: u32,
        height: u32,
        samples: u32,
        depth: crate::gl::Format,
    ) -> SparseMemory {
        use super::targets::{BLOCK_BYTES, COUNTER_BYTES, HEAD_BYTES};
        let pixels = u64::from(width) * u64::from(height);
        let pool = u64::from(options.pool_capacity(width, height).max(1));
        SparseMemory {
            heads: pixels * HEAD_BYTES,
            first_blocks: pixels * BLOCK_BYTES,
            pool: pool * BLOCK_BYTES,
            depth: pixels * u64::from(samples) * u64::from(prepass_format(depth).bytes_per_texel()),
            counters: COUNTER_BYTES as u64,
        }
    }

    /// Everything together.
    pub fn total(&self) -> u64 {
        self.heads + self.first_blocks + self.pool + self.depth + self.counters
    }
}

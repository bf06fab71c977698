//! What the context can do: versions, limits, real sample counts and positions.

use super::samples::get_u32;
use super::{Attachment, Format, RenderTarget, check_error};
use crate::Result;
use glow::HasContext;
use std::ffi::c_void;

type GetMultisamplefv = unsafe extern "system" fn(pname: u32, index: u32, val: *mut f32);
type ClipControl = unsafe extern "system" fn(origin: u32, depth: u32);

/// Entry points glow does not wrap, loaded through the host's loader.
#[derive(Clone, Copy, Debug, Default)]
pub struct ExtraFns {
    get_multisamplefv: Option<GetMultisamplefv>,
    clip_control: Option<ClipControl>,
}

impl ExtraFns {
    /// Load through `loader` (e.g. `eglGetProcAddress`); absent functions stay `None`.
    pub fn load(gl: &glow::Context, loader: impl Fn(&str) -> *const c_void) -> Self {
        let v = gl.version();
        let clip_control_exists = (v.major, v.minor) >= (4, 5)
            || gl.supported_extensions().contains("GL_ARB_clip_control");
        // SAFETY: a non-null pointer returned for these names has the documented GL signature.
        unsafe {
            let ms = loader("glGetMultisamplefv");
            let cc = if clip_control_exists {
                loader("glClipControl")
            } else {
                std::ptr::null()
            };
            ExtraFns {
                get_multisamplefv: (!ms.is_null())
                    .then(|| std::mem::transmute::<*const c_void, GetMultisamplefv>(ms)),
                clip_control: (!cc.is_null())
                    .then(|| std::mem::transmute::<*const c_void, ClipControl>(cc)),
            }
        }
    }

    /// Whether `glClipControl` is available (GL 4.5 or ARB_clip_control).
    pub fn has_clip_control(&self) -> bool {
        self.clip_control.is_some()
    }

    /// `glClipControl(GL_LOWER_LEFT, zero_to_one ? GL_ZERO_TO_ONE : GL_NEGATIVE_ONE_TO_ONE)`;
    /// returns `false` when the context lacks it.
    pub fn set_clip_depth_zero_to_one(&self, zero_to_one: bool) -> bool {
        match self.clip_control {
            Some(f) => {
                let depth = if zero_to_one {
                    glow::ZERO_TO_ONE
                } else {
                    glow::NEGATIVE_ONE_TO_ONE
                };
                // SAFETY: loaded for this context; arguments are valid enums.
                unsafe { f(glow::LOWER_LEFT, depth) };
                true
            }
            None => false,
        }
    }
}

/// Limits and features of the current context.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Capabilities {
    /// `GL_VERSION`.
    pub gl_version: String,
    /// `GL_SHADING_LANGUAGE_VERSION`.
    pub glsl_version: String,
    /// `GL_RENDERER`.
    pub renderer: String,
    /// `GL_VENDOR`.
    pub vendor: String,
    /// Parsed major and minor version.
    pub version: (u32, u32),
    /// `GL_MAX_SAMPLES`.
    pub max_samples: u32,
    /// `GL_MAX_COLOR_TEXTURE_SAMPLES`.
    pub max_color_texture_samples: u32,
    /// `GL_MAX_DEPTH_TEXTURE_SAMPLES`.
    pub max_depth_texture_samples: u32,
    /// `GL_MAX_INTEGER_SAMPLES`.
    pub max_integer_samples: u32,
    /// `GL_MAX_TEXTURE_SIZE`.
    pub max_texture_size: u32,
    /// `GL_MAX_DRAW_BUFFERS`.
    pub max_draw_buffers: u32,
    /// `GL_MAX_COLOR_ATTACHMENTS`.
    pub max_color_attachments: u32,
    /// `GL_TIME_ELAPSED` queries.
    pub timer_query: bool,
    /// `glGetInternalformativ` (GL 4.2 or ARB_internalformat_query).
    pub internalformat_query: bool,
    /// `gl_SampleMaskIn` in fragment shaders (GL 4.0 or ARB_gpu_shader5 / ARB_sample_shading).
    pub sample_mask_in: bool,
    /// Shader storage buffers and atomic counters (GL 4.3).
    pub storage_buffers: bool,
    /// KHR_debug.
    pub khr_debug: bool,
    /// `glClipControl` (GL 4.5 or ARB_clip_control): reversed-Z with full float precision.
    pub clip_control: bool,
}

impl Capabilities {
    /// Query the current context.
    pub fn query(gl: &glow::Context) -> Self {
        let v = gl.version();
        let version = (v.major, v.minor);
        let ext = gl.supported_extensions();
        let (gl_version, glsl_version, renderer, vendor) = unsafe {
            (
                gl.get_parameter_string(glow::VERSION),
                gl.get_parameter_string(glow::SHADING_LANGUAGE_VERSION),
                gl.get_parameter_string(glow::RENDERER),
                gl.get_parameter_string(glow::VENDOR),
            )
        };
        let caps = Capabilities {
            gl_version,
            glsl_version,
            renderer,
            vendor,
            version,
            max_samples: get_u32(gl, glow::MAX_SAMPLES),
            max_color_texture_samples: get_u32(gl, glow::MAX_COLOR_TEXTURE_SAMPLES),
            max_depth_texture_samples: get_u32(gl, glow::MAX_DEPTH_TEXTURE_SAMPLES),
            max_integer_samples: get_u32(gl, glow::MAX_INTEGER_SAMPLES),
            max_texture_size: get_u32(gl, glow::MAX_TEXTURE_SIZE),
            max_draw_buffers: get_u32(gl, glow::MAX_DRAW_BUFFERS),
            max_color_attachments: get_u32(gl, glow::MAX_COLOR_ATTACHMENTS),
            timer_query: version >= (3, 3) || ext.contains("GL_ARB_timer_query"),
            internalformat_query: version >= (4, 2) || ext.contains("GL_ARB_internalformat_query"),
            sample_mask_in: version >= (4, 0)
                || ext.contains("GL_ARB_gpu_shader5")
                || ext.contains("GL_ARB_sample_shading"),
            storage_buffers: version >= (4, 3),
            khr_debug: version >= (4, 3) || ext.contains("GL_KHR_debug"),
            clip_control: version >= (4, 5) || ext.contains("GL_ARB_clip_control"),
        };
        // Drain anything an unknown enum left behind on older contexts.
        let _ = check_error(gl, "querying capabilities");
        caps
    }

    /// The distinct sample counts a `GL_TEXTURE_2D_MULTISAMPLE` of `format`
    /// really gets, ascending. Candidates come from `glGetInternalformativ`
    /// where the context has it, else the powers of two up to the format's
    /// `GL_MAX_*_SAMPLES`; each is then allocated at 1x1 and read back, because
    /// drivers round requests.
    pub fn sample_counts_for(gl: &glow::Context, format: Format) -> Vec<u32> {
        super::samples::sample_counts_for(gl, format)
    }
}

/// The sample positions (in pixel units, 0..1) of an `samples`-sample colour
/// framebuffer, read with `glGetMultisamplefv(GL_SAMPLE_POSITION)`. Returns
/// the real count and the positions; an empty list when the entry point is missing.
pub fn sample_positions(
    gl: &glow::Context,
    extra: &ExtraFns,
    samples: u32,
) -> Result<(u32, Vec<[f32; 2]>)> {
    let probe = RenderTarget::multisample(
        gl,
        "sample-position probe",
        1,
        1,
        samples,
        &[(Attachment::Color(0), Format::Rgba8)],
        &[Some(0)],
    )?;
    let real = probe.samples();
    let mut positions = Vec::new();
    if let Some(f) = extra.get_multisamplefv {
        unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, Some(probe.fbo().raw)) };
        let n = get_u32(gl, glow::SAMPLES);
        for i in 0..n {
            let mut xy = [0.0f32; 2];
            // SAFETY: `xy` holds the two floats GL_SAMPLE_POSITION writes.
            unsafe { f(glow::SAMPLE_POSITION, i, xy.as_mut_ptr()) };
            positions.push(xy);
        }
        unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, None) };
    }
    probe.destroy(gl);
    check_error(gl, "reading sample positions")?;
    Ok((real, positions))
}

/// The colour attachment points (and draw buffers) a framebuffer of this
/// context may use: the smaller of `GL_MAX_COLOR_ATTACHMENTS` and
/// `GL_MAX_DRAW_BUFFERS`.
pub(crate) fn output_points(gl: &glow::Context) -> u32 {
    let (attachments, draw) = unsafe {
        (
            glow::HasContext::get_parameter_i32(gl, glow::MAX_COLOR_ATTACHMENTS),
            glow::HasContext::get_parameter_i32(gl, glow::MAX_DRAW_BUFFERS),
        )
    };
    attachments.min(draw).max(1) as u32
}

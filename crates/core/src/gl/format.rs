//! The internal formats the crate knows, with what each needs for allocation,
//! reading back and resolving.

/// An internal texture format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[allow(missing_docs)] // the variants are the GL names
pub enum Format {
    R8,
    Rg8,
    Rgba8,
    Srgb8Alpha8,
    Rgb10A2,
    R16f,
    Rg16f,
    Rgba16f,
    R11fG11fB10f,
    R32f,
    Rg32f,
    Rgba32f,
    R32ui,
    Rgba8ui,
    Rgba16ui,
    Rgba32ui,
    Rgba32i,
    Depth16,
    Depth24,
    Depth32f,
    Depth24Stencil8,
    Depth32fStencil8,
}

/// How a shader sees a format's values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SampleKind {
    /// Normalised or floating point: `sampler*`, `vec4`.
    Float,
    /// Unsigned integer: `usampler*`, `uvec4`.
    Uint,
    /// Signed integer: `isampler*`, `ivec4`.
    Int,
}

impl Format {
    /// Every known format.
    pub const ALL: &'static [Format] = &[
        Format::R8,
        Format::Rg8,
        Format::Rgba8,
        Format::Srgb8Alpha8,
        Format::Rgb10A2,
        Format::R16f,
        Format::Rg16f,
        Format::Rgba16f,
        Format::R11fG11fB10f,
        Format::R32f,
        Format::Rg32f,
        Format::Rgba32f,
        Format::R32ui,
        Format::Rgba8ui,
        Format::Rgba16ui,
        Format::Rgba32ui,
        Format::Rgba32i,
        Format::Depth16,
        Format::Depth24,
        Format::Depth32f,
        Format::Depth24Stencil8,
        Format::Depth32fStencil8,
    ];

    /// `(internal format, pixel format, pixel type, bytes per texel, name)`.
    const fn table(self) -> (u32, u32, u32, u32, &'static str) {
        use Format::*;
        match self {
            R8 => (glow::R8, glow::RED, glow::UNSIGNED_BYTE, 1, "R8"),
            Rg8 => (glow::RG8, glow::RG, glow::UNSIGNED_BYTE, 2, "RG8"),
            Rgba8 => (glow::RGBA8, glow::RGBA, glow::UNSIGNED_BYTE, 4, "RGBA8"),
            Srgb8Alpha8 => (
                glow::SRGB8_ALPHA8,
                glow::RGBA,
                glow::UNSIGNED_BYTE,
                4,
                "SRGB8_ALPHA8",
            ),
            Rgb10A2 => (
                glow::RGB10_A2,
                glow::RGBA,
                glow::UNSIGNED_INT_2_10_10_10_REV,
                4,
                "RGB10_A2",
            ),
            R16f => (glow::R16F, glow::RED, glow::HALF_FLOAT, 2, "R16F"),
            Rg16f => (glow::RG16F, glow::RG, glow::HALF_FLOAT, 4, "RG16F"),
            Rgba16f => (glow::RGBA16F, glow::RGBA, glow::HALF_FLOAT, 8, "RGBA16F"),
            R11fG11fB10f => (
                glow::R11F_G11F_B10F,
                glow::RGB,
                glow::FLOAT,
                4,
                "R11F_G11F_B10F",
            ),
            R32f => (glow::R32F, glow::RED, glow::FLOAT, 4, "R32F"),
            Rg32f => (glow::RG32F, glow::RG, glow::FLOAT, 8, "RG32F"),
            Rgba32f => (glow::RGBA32F, glow::RGBA, glow::FLOAT, 16, "RGBA32F"),
            R32ui => (
                glow::R32UI,
                glow::RED_INTEGER,
                glow::UNSIGNED_INT,
                4,
                "R32UI",
            ),
            Rgba8ui => (
                glow::RGBA8UI,
                glow::RGBA_INTEGER,
                glow::UNSIGNED_BYTE,
                4,
                "RGBA8UI",
            ),
            Rgba16ui => (
                glow::RGBA16UI,
                glow::RGBA_INTEGER,
                glow::UNSIGNED_SHORT,
                8,
                "RGBA16UI",
            ),
            Rgba32ui => (
                glow::RGBA32UI,
                glow::RGBA_INTEGER,
                glow::UNSIGNED_INT,
                16,
                "RGBA32UI",
            ),
            Rgba32i => (glow::RGBA32I, glow::RGBA_INTEGER, glow::INT, 16, "RGBA32I"),
            Depth16 => (
                glow::DEPTH_COMPONENT16,
                glow::DEPTH_COMPONENT,
                glow::UNSIGNED_SHORT,
                2,
                "DEPTH_COMPONENT16",
            ),
            Depth24 => (
                glow::DEPTH_COMPONENT24,
                glow::DEPTH_COMPONENT,
                glow::UNSIGNED_INT,
                4,
                "DEPTH_COMPONENT24",
            ),
            Depth32f => (
                glow::DEPTH_COMPONENT32F,
                glow::DEPTH_COMPONENT,
                glow::FLOAT,
                4,
                "DEPTH_COMPONENT32F",
            ),
            Depth24Stencil8 => (
                glow::DEPTH24_STENCIL8,
                glow::DEPTH_STENCIL,
                glow::UNSIGNED_INT_24_8,
                4,
                "DEPTH24_STENCIL8",
            ),
            Depth32fStencil8 => (
                glow::DEPTH32F_STENCIL8,
                glow::DEPTH_STENCIL,
                glow::FLOAT_32_UNSIGNED_INT_24_8_REV,
                8,
                "DEPTH32F_STENCIL8",
            ),
        }
    }

    /// The GL internal format enum.
    pub const fn internal_format(self) -> u32 {
        self.table().0
    }
    /// The pixel format used to allocate storage.
    pub const fn pixel_format(self) -> u32 {
        self.table().1
    }
    /// The pixel type used to allocate storage.
    pub const fn pixel_type(self) -> u32 {
        self.table().2
    }
    /// Bytes per texel (per sample, for multisample textures), as allocated by a typical driver.
    pub const fn bytes_per_texel(self) -> u32 {
        self.table().3
    }
    /// The GL name without the `GL_` prefix, e.g. `RGBA16F`.
    pub const fn name(self) -> &'static str {
        self.table().4
    }

    /// The format of a GL internal format enum, if the crate knows it.
    pub fn from_internal_format(value: u32) -> Option<Format> {
        Format::ALL
            .iter()
            .copied()
            .find(|f| f.internal_format() == value)
    }

    /// Look a format up by its name (case-insensitive, `GL_` prefix optional).
    pub fn from_name(name: &str) -> Option<Format> {
        let upper = name.trim().to_ascii_uppercase();
        let bare = upper.strip_prefix("GL_").unwrap_or(&upper);
        Format::ALL
            .iter()
            .copied()
            .find(|f| f.name() == bare || f.name().replace("_COMPONENT", "") == bare)
    }

    /// Number of components (depth formats: 1).
    pub const fn channels(self) -> u32 {
        use Format::*;
        match self {
            R8 | R16f | R32f | R32ui | Depth16 | Depth24 | Depth32f | Depth24Stencil8
            | Depth32fStencil8 => 1,
            Rg8 | Rg16f | Rg32f => 2,
            R11fG11fB10f => 3,
            _ => 4,
        }
    }

    /// A depth or depth-stencil format.
    pub const fn is_depth(self) -> bool {
        matches!(
            self,
            Format::Depth16
                | Format::Depth24
                | Format::Depth32f
                | Format::Depth24Stencil8
                | Format::Depth32fStencil8
        )
    }

    /// A combined depth-stencil format.
    pub const fn has_stencil(self) -> bool {
        matches!(self, Format::Depth24Stencil8 | Format::Depth32fStencil8)
    }

    /// How shaders read it.
    pub const fn sample_kind(self) -> SampleKind {
        match self {
            Format::R32ui | Format::Rgba8ui | Format::Rgba16ui | Format::Rgba32ui => {
                SampleKind::Uint
            }
            Format::Rgba32i => SampleKind::Int,
            _ => SampleKind::Float,
        }
    }

    /// Half-float storage (values beyond ±65504 overflow to infinity).
    pub const fn is_half_float(self) -> bool {
        matches!(
            self,
            Format::R16f | Format::Rg16f | Format::Rgba16f | Format::R11fG11fB10f
        )
    }

    /// The GLSL sampler prefix: `""`, `"u"` or `"i"`.
    pub const fn glsl_prefix(self) -> &'static str {
        match self.sample_kind() {
            SampleKind::Float => "",
            SampleKind::Uint => "u",
            SampleKind::Int => "i",
        }
    }
}

impl std::fmt::Display for Format {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for &f in Format::ALL {
            assert_eq!(Format::from_name(f.name()), Some(f));
            assert_eq!(Format::from_internal_format(f.internal_format()), Some(f));
        }
        assert_eq!(Format::from_name("gl_rgba16f"), Some(Format::Rgba16f));
        assert_eq!(Format::from_name("DEPTH24"), Some(Format::Depth24));
        assert_eq!(Format::from_name("RGBA9"), None);
    }
}

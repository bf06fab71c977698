//! The internal formats the crate knows, found by what they are.
//!
//! A format is known by its GL enum, and also by its properties as the
//! driver reports them for an attachment (component type, colour encoding,
//! bits per channel, depth and stencil bits): that is how unsized formats
//! (`GL_RGBA`, `GL_DEPTH_COMPONENT`) and renderbuffers are recognised.

/// An internal texture format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[allow(missing_docs)] // the variants are the GL names
pub enum Format {
    R8,
    Rg8,
    Rgb8,
    Rgba8,
    Srgb8,
    Srgb8Alpha8,
    Rgb10A2,
    R16,
    Rg16,
    Rgba16,
    R8Snorm,
    Rg8Snorm,
    Rgba8Snorm,
    R16Snorm,
    Rg16Snorm,
    Rgba16Snorm,
    R16f,
    Rg16f,
    Rgb16f,
    Rgba16f,
    R11fG11fB10f,
    R32f,
    Rg32f,
    Rgb32f,
    Rgba32f,
    R8ui,
    R16ui,
    R32ui,
    Rg32ui,
    Rgba8ui,
    Rgba16ui,
    Rgba32ui,
    R32i,
    Rgba32i,
    Depth16,
    Depth24,
    Depth32,
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

/// A format's component type, as `GL_FRAMEBUFFER_ATTACHMENT_COMPONENT_TYPE`
/// (or `GL_TEXTURE_RED_TYPE`) reports it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ComponentType {
    /// `GL_UNSIGNED_NORMALIZED`.
    Unorm,
    /// `GL_SIGNED_NORMALIZED`.
    Snorm,
    /// `GL_FLOAT`.
    Float,
    /// `GL_UNSIGNED_INT`.
    Uint,
    /// `GL_INT`.
    Int,
}

impl ComponentType {
    /// From the GL enum.
    pub fn from_gl(value: u32) -> Option<Self> {
        Some(match value {
            glow::UNSIGNED_NORMALIZED => ComponentType::Unorm,
            glow::SIGNED_NORMALIZED => ComponentType::Snorm,
            glow::FLOAT => ComponentType::Float,
            glow::UNSIGNED_INT => ComponentType::Uint,
            glow::INT => ComponentType::Int,
            _ => return None,
        })
    }
}

/// What the driver says an attachment's image is: the properties a format
/// is recognised by.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct FormatProperties {
    /// The component type (of the depth component for depth formats).
    pub component: ComponentType,
    /// Bits of red, green, blue and alpha.
    pub rgba_bits: [u32; 4],
    /// Bits of depth.
    pub depth_bits: u32,
    /// Bits of stencil.
    pub stencil_bits: u32,
    /// sRGB colour encoding.
    pub srgb: bool,
}

impl Format {
    /// Every known format.
    pub const ALL: &'static [Format] = &[
        Format::R8,
        Format::Rg8,
        Format::Rgb8,
        Format::Rgba8,
        Format::Srgb8,
        Format::Srgb8Alpha8,
        Format::Rgb10A2,
        Format::R16,
        Format::Rg16,
        Format::Rgba16,
        Format::R8Snorm,
        Format::Rg8Snorm,
        Format::Rgba8Snorm,
        Format::R16Snorm,
        Format::Rg16Snorm,
        Format::Rgba16Snorm,
        Format::R16f,
        Format::Rg16f,
        Format::Rgb16f,
        Format::Rgba16f,
        Format::R11fG11fB10f,
        Format::R32f,
        Format::Rg32f,
        Format::Rgb32f,
        Format::Rgba32f,
        Format::R8ui,
        Format::R16ui,
        Format::R32ui,
        Format::Rg32ui,
        Format::Rgba8ui,
        Format::Rgba16ui,
        Format::Rgba32ui,
        Format::R32i,
        Format::Rgba32i,
        Format::Depth16,
        Format::Depth24,
        Format::Depth32,
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
            Rgb8 => (glow::RGB8, glow::RGB, glow::UNSIGNED_BYTE, 4, "RGB8"),
            Rgba8 => (glow::RGBA8, glow::RGBA, glow::UNSIGNED_BYTE, 4, "RGBA8"),
            Srgb8 => (glow::SRGB8, glow::RGB, glow::UNSIGNED_BYTE, 4, "SRGB8"),
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
            R16 => (glow::R16, glow::RED, glow::UNSIGNED_SHORT, 2, "R16"),
            Rg16 => (glow::RG16, glow::RG, glow::UNSIGNED_SHORT, 4, "RG16"),
            Rgba16 => (glow::RGBA16, glow::RGBA, glow::UNSIGNED_SHORT, 8, "RGBA16"),
            R8Snorm => (glow::R8_SNORM, glow::RED, glow::BYTE, 1, "R8_SNORM"),
            Rg8Snorm => (glow::RG8_SNORM, glow::RG, glow::BYTE, 2, "RG8_SNORM"),
            Rgba8Snorm => (glow::RGBA8_SNORM, glow::RGBA, glow::BYTE, 4, "RGBA8_SNORM"),
            R16Snorm => (glow::R16_SNORM, glow::RED, glow::SHORT, 2, "R16_SNORM"),
            Rg16Snorm => (glow::RG16_SNORM, glow::RG, glow::SHORT, 4, "RG16_SNORM"),
            Rgba16Snorm => (
                glow::RGBA16_SNORM,
                glow::RGBA,
                glow::SHORT,
                8,
                "RGBA16_SNORM",
            ),
            R16f => (glow::R16F, glow::RED, glow::HALF_FLOAT, 2, "R16F"),
            Rg16f => (glow::RG16F, glow::RG, glow::HALF_FLOAT, 4, "RG16F"),
            Rgb16f => (glow::RGB16F, glow::RGB, glow::HALF_FLOAT, 8, "RGB16F"),
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
            Rgb32f => (glow::RGB32F, glow::RGB, glow::FLOAT, 16, "RGB32F"),
            Rgba32f => (glow::RGBA32F, glow::RGBA, glow::FLOAT, 16, "RGBA32F"),
            R8ui => (
                glow::R8UI,
                glow::RED_INTEGER,
                glow::UNSIGNED_BYTE,
                1,
                "R8UI",
            ),
            R16ui => (
                glow::R16UI,
                glow::RED_INTEGER,
                glow::UNSIGNED_SHORT,
                2,
                "R16UI",
            ),
            R32ui => (
                glow::R32UI,
                glow::RED_INTEGER,
                glow::UNSIGNED_INT,
                4,
                "R32UI",
            ),
            Rg32ui => (
                glow::RG32UI,
                glow::RG_INTEGER,
                glow::UNSIGNED_INT,
                8,
                "RG32UI",
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
            R32i => (glow::R32I, glow::RED_INTEGER, glow::INT, 4, "R32I"),
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
            Depth32 => (
                glow::DEPTH_COMPONENT32,
                glow::DEPTH_COMPONENT,
                glow::UNSIGNED_INT,
                4,
                "DEPTH_COMPONENT32",
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

    /// What the format is: component type, bits, encoding.
    pub const fn properties(self) -> FormatProperties {
        use Format::*;
        let (component, rgba_bits, depth_bits, stencil_bits, srgb) = match self {
            R8 => (ComponentType::Unorm, [8, 0, 0, 0], 0, 0, false),
            Rg8 => (ComponentType::Unorm, [8, 8, 0, 0], 0, 0, false),
            Rgb8 => (ComponentType::Unorm, [8, 8, 8, 0], 0, 0, false),
            Rgba8 => (ComponentType::Unorm, [8, 8, 8, 8], 0, 0, false),
            Srgb8 => (ComponentType::Unorm, [8, 8, 8, 0], 0, 0, true),
            Srgb8Alpha8 => (ComponentType::Unorm, [8, 8, 8, 8], 0, 0, true),
            Rgb10A2 => (ComponentType::Unorm, [10, 10, 10, 2], 0, 0, false),
            R16 => (ComponentType::Unorm, [16, 0, 0, 0], 0, 0, false),
            Rg16 => (ComponentType::Unorm, [16, 16, 0, 0], 0, 0, false),
            Rgba16 => (ComponentType::Unorm, [16, 16, 16, 16], 0, 0, false),
            R8Snorm => (ComponentType::Snorm, [8, 0, 0, 0], 0, 0, false),
            Rg8Snorm => (ComponentType::Snorm, [8, 8, 0, 0], 0, 0, false),
            Rgba8Snorm => (ComponentType::Snorm, [8, 8, 8, 8], 0, 0, false),
            R16Snorm => (ComponentType::Snorm, [16, 0, 0, 0], 0, 0, false),
            Rg16Snorm => (ComponentType::Snorm, [16, 16, 0, 0], 0, 0, false),
            Rgba16Snorm => (ComponentType::Snorm, [16, 16, 16, 16], 0, 0, false),
            R16f => (ComponentType::Float, [16, 0, 0, 0], 0, 0, false),
            Rg16f => (ComponentType::Float, [16, 16, 0, 0], 0, 0, false),
            Rgb16f => (ComponentType::Float, [16, 16, 16, 0], 0, 0, false),
            Rgba16f => (ComponentType::Float, [16, 16, 16, 16], 0, 0, false),
            R11fG11fB10f => (ComponentType::Float, [11, 11, 10, 0], 0, 0, false),
            R32f => (ComponentType::Float, [32, 0, 0, 0], 0, 0, false),
            Rg32f => (ComponentType::Float, [32, 32, 0, 0], 0, 0, false),
            Rgb32f => (ComponentType::Float, [32, 32, 32, 0], 0, 0, false),
            Rgba32f => (ComponentType::Float, [32, 32, 32, 32], 0, 0, false),
            R8ui => (ComponentType::Uint, [8, 0, 0, 0], 0, 0, false),
            R16ui => (ComponentType::Uint, [16, 0, 0, 0], 0, 0, false),
            R32ui => (ComponentType::Uint, [32, 0, 0, 0], 0, 0, false),
            Rg32ui => (ComponentType::Uint, [32, 32, 0, 0], 0, 0, false),
            Rgba8ui => (ComponentType::Uint, [8, 8, 8, 8], 0, 0, false),
            Rgba16ui => (ComponentType::Uint, [16, 16, 16, 16], 0, 0, false),
            Rgba32ui => (ComponentType::Uint, [32, 32, 32, 32], 0, 0, false),
            R32i => (ComponentType::Int, [32, 0, 0, 0], 0, 0, false),
            Rgba32i => (ComponentType::Int, [32, 32, 32, 32], 0, 0, false),
            Depth16 => (ComponentType::Unorm, [0, 0, 0, 0], 16, 0, false),
            Depth24 => (ComponentType::Unorm, [0, 0, 0, 0], 24, 0, false),
            Depth32 => (ComponentType::Unorm, [0, 0, 0, 0], 32, 0, false),
            Depth32f => (ComponentType::Float, [0, 0, 0, 0], 32, 0, false),
            Depth24Stencil8 => (ComponentType::Unorm, [0, 0, 0, 0], 24, 8, false),
            Depth32fStencil8 => (ComponentType::Float, [0, 0, 0, 0], 32, 8, false),
        };
        FormatProperties {
            component,
            rgba_bits,
            depth_bits,
            stencil_bits,
            srgb,
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

    /// The format of a sized GL internal format enum, if the crate knows it.
    pub fn from_internal_format(value: u32) -> Option<Format> {
        Format::ALL
            .iter()
            .copied()
            .find(|f| f.internal_format() == value)
    }

    /// The format an image with these properties has: how unsized internal
    /// formats (`GL_RGBA`, `GL_DEPTH_COMPONENT`, …) and renderbuffers are
    /// recognised, from what the driver made of them.
    pub fn from_properties(p: &FormatProperties) -> Option<Format> {
        Format::ALL.iter().copied().find(|f| f.properties() == *p)
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
        let p = self.properties();
        if p.depth_bits > 0 {
            return 1;
        }
        let b = p.rgba_bits;
        (b[0] > 0) as u32 + (b[1] > 0) as u32 + (b[2] > 0) as u32 + (b[3] > 0) as u32
    }

    /// A depth or depth-stencil format.
    pub const fn is_depth(self) -> bool {
        self.properties().depth_bits > 0
    }

    /// A combined depth-stencil format.
    pub const fn has_stencil(self) -> bool {
        self.properties().stencil_bits > 0
    }

    /// sRGB-encoded: shaders read decoded (linear) values, and writes are
    /// encoded only while `GL_FRAMEBUFFER_SRGB` is enabled.
    pub const fn is_srgb(self) -> bool {
        self.properties().srgb
    }

    /// The same bits without the sRGB encoding (`SRGB8_ALPHA8` as
    /// `RGBA8`): a copy that reads and writes them as stored. Any other
    /// format is itself.
    pub const fn without_srgb(self) -> Format {
        match self {
            Format::Srgb8 => Format::Rgb8,
            Format::Srgb8Alpha8 => Format::Rgba8,
            other => other,
        }
    }

    /// How shaders read it.
    pub const fn sample_kind(self) -> SampleKind {
        match self.properties().component {
            ComponentType::Uint => SampleKind::Uint,
            ComponentType::Int => SampleKind::Int,
            _ => SampleKind::Float,
        }
    }

    /// Half-float storage (values beyond ±65504 overflow to infinity).
    pub const fn is_half_float(self) -> bool {
        matches!(
            self,
            Format::R16f | Format::Rg16f | Format::Rgb16f | Format::Rgba16f | Format::R11fG11fB10f
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

    /// A wider format whose multisampled texture can stand in for this one
    /// where the driver cannot multisample it (three-channel and snorm
    /// formats need not be colour-renderable as multisample textures in
    /// GL 3.2). Every value the host's shader writes survives it
    /// unchanged: the resolve then writes into the host's own texture, whose
    /// conversion stores what the host's geometry pass would have.
    pub const fn multisample_stand_in(self) -> Option<Format> {
        use Format::*;
        Some(match self {
            Rgb8 => Rgba8,
            Srgb8 => Srgb8Alpha8,
            Rgb16f => Rgba16f,
            // A float twin keeps the shader's output exactly, so the host
            // texture's own snorm (or unorm) conversion happens once, at the
            // resolve, as it would have in the host's geometry pass.
            R8Snorm | R16Snorm | R16 => R32f,
            Rg8Snorm | Rg16Snorm | Rg16 => Rg32f,
            Rgba8Snorm | Rgba16Snorm | Rgba16 => Rgba32f,
            Rgb32f => Rgba32f,
            _ => return None,
        })
    }
}

/// The name of a GL internal format enum, with the `GL_` prefix: the crate's
/// formats, the unsized ones and others engines use, so that an error names
/// what the host wrote (`GL_RGBA`, not `0x1908`).
pub fn internal_format_name(value: u32) -> String {
    if let Some(f) = Format::from_internal_format(value) {
        return format!("GL_{}", f.name());
    }
    let name = match value {
        glow::RED => "GL_RED",
        glow::RG => "GL_RG",
        glow::RGB => "GL_RGB",
        glow::RGBA => "GL_RGBA",
        glow::DEPTH_COMPONENT => "GL_DEPTH_COMPONENT",
        glow::DEPTH_STENCIL => "GL_DEPTH_STENCIL",
        glow::STENCIL_INDEX => "GL_STENCIL_INDEX",
        glow::STENCIL_INDEX8 => "GL_STENCIL_INDEX8",
        glow::R3_G3_B2 => "GL_R3_G3_B2",
        glow::RGB4 => "GL_RGB4",
        glow::RGB5 => "GL_RGB5",
        glow::RGB565 => "GL_RGB565",
        glow::RGB10 => "GL_RGB10",
        glow::RGB12 => "GL_RGB12",
        glow::RGB16 => "GL_RGB16",
        glow::RGBA2 => "GL_RGBA2",
        glow::RGBA4 => "GL_RGBA4",
        glow::RGB5_A1 => "GL_RGB5_A1",
        glow::RGBA12 => "GL_RGBA12",
        glow::RGB9_E5 => "GL_RGB9_E5",
        glow::RGB10_A2UI => "GL_RGB10_A2UI",
        glow::RGB8_SNORM => "GL_RGB8_SNORM",
        glow::RGB16_SNORM => "GL_RGB16_SNORM",
        glow::R8I => "GL_R8I",
        glow::R16I => "GL_R16I",
        glow::RG8I => "GL_RG8I",
        glow::RG8UI => "GL_RG8UI",
        glow::RG16I => "GL_RG16I",
        glow::RG16UI => "GL_RG16UI",
        glow::RG32I => "GL_RG32I",
        glow::RGB8I => "GL_RGB8I",
        glow::RGB8UI => "GL_RGB8UI",
        glow::RGB16I => "GL_RGB16I",
        glow::RGB16UI => "GL_RGB16UI",
        glow::RGB32I => "GL_RGB32I",
        glow::RGB32UI => "GL_RGB32UI",
        glow::RGBA8I => "GL_RGBA8I",
        glow::RGBA16I => "GL_RGBA16I",
        glow::STENCIL_INDEX1 => "GL_STENCIL_INDEX1",
        glow::STENCIL_INDEX4 => "GL_STENCIL_INDEX4",
        glow::STENCIL_INDEX16 => "GL_STENCIL_INDEX16",
        glow::COMPRESSED_RGBA => "GL_COMPRESSED_RGBA",
        glow::COMPRESSED_RGB => "GL_COMPRESSED_RGB",
        glow::COMPRESSED_SRGB_ALPHA => "GL_COMPRESSED_SRGB_ALPHA",
        _ => return format!("internal format 0x{value:04X}"),
    };
    name.to_string()
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

    #[test]
    fn properties_identify_every_format() {
        for &f in Format::ALL {
            assert_eq!(Format::from_properties(&f.properties()), Some(f), "{f}");
        }
        let rgba8 = FormatProperties {
            component: ComponentType::Unorm,
            rgba_bits: [8, 8, 8, 8],
            depth_bits: 0,
            stencil_bits: 0,
            srgb: false,
        };
        assert_eq!(Format::from_properties(&rgba8), Some(Format::Rgba8));
        assert_eq!(internal_format_name(glow::RGBA), "GL_RGBA");
        assert_eq!(internal_format_name(glow::RG16_SNORM), "GL_RG16_SNORM");
    }

    #[test]
    fn stand_ins_are_wider_and_of_the_same_kind() {
        for &f in Format::ALL {
            if let Some(s) = f.multisample_stand_in() {
                assert_eq!(s.sample_kind(), f.sample_kind(), "{f}");
                assert!(s.channels() >= f.channels(), "{f}");
                assert_eq!(s.is_srgb(), f.is_srgb(), "{f}");
                assert!(s.multisample_stand_in().is_none(), "{f}: one step");
            }
        }
    }
}

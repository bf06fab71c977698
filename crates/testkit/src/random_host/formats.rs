//! The internal formats a host may ask for, colour and depth, as a table.

/// An internal format a host may ask for: its enum, its name, and the
/// pixel format and type it allocates texture storage with.
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct HostFormat {
    /// The internal format enum as passed to `glTexImage2D` /
    /// `glRenderbufferStorage`.
    pub internal: u32,
    /// Its GL name, e.g. `GL_RGBA` or `GL_R11F_G11F_B10F`.
    pub name: &'static str,
    /// The pixel format of the (empty) upload.
    pub pixel: u32,
    /// The pixel type of the (empty) upload.
    pub ty: u32,
}

pub(super) const fn f(internal: u32, name: &'static str, pixel: u32, ty: u32) -> HostFormat {
    HostFormat {
        internal,
        name,
        pixel,
        ty,
    }
}

/// Every colour internal format GL 3.2–4.5 defines that an engine could
/// attach: the unsized base formats with the types tutorials pass, the
/// sized normalised, snorm, unorm16, float, packed, sRGB and integer
/// ones. Some are not required to be colour-renderable (the snorm and
/// three-channel ones, `GL_RGB9_E5`, the `RGB*I` family): a driver may
/// refuse them, and such a host is counted as incomplete, not retrofitted.
pub const COLOR_FORMATS: &[HostFormat] = &[
    f(glow::RGBA, "GL_RGBA", glow::RGBA, glow::UNSIGNED_BYTE),
    f(glow::RGBA, "GL_RGBA", glow::RGBA, glow::FLOAT),
    f(glow::RGB, "GL_RGB", glow::RGB, glow::UNSIGNED_BYTE),
    f(glow::RGB, "GL_RGB", glow::RGB, glow::FLOAT),
    f(glow::RG, "GL_RG", glow::RG, glow::UNSIGNED_BYTE),
    f(glow::RED, "GL_RED", glow::RED, glow::UNSIGNED_BYTE),
    f(glow::R8, "GL_R8", glow::RED, glow::UNSIGNED_BYTE),
    f(glow::RG8, "GL_RG8", glow::RG, glow::UNSIGNED_BYTE),
    f(glow::RGB8, "GL_RGB8", glow::RGB, glow::UNSIGNED_BYTE),
    f(glow::RGBA8, "GL_RGBA8", glow::RGBA, glow::UNSIGNED_BYTE),
    f(
        glow::R3_G3_B2,
        "GL_R3_G3_B2",
        glow::RGB,
        glow::UNSIGNED_BYTE,
    ),
    f(glow::RGB4, "GL_RGB4", glow::RGB, glow::UNSIGNED_BYTE),
    f(glow::RGB5, "GL_RGB5", glow::RGB, glow::UNSIGNED_BYTE),
    f(glow::RGB565, "GL_RGB565", glow::RGB, glow::UNSIGNED_BYTE),
    f(glow::RGB10, "GL_RGB10", glow::RGB, glow::UNSIGNED_SHORT),
    f(glow::RGB12, "GL_RGB12", glow::RGB, glow::UNSIGNED_SHORT),
    f(glow::RGBA2, "GL_RGBA2", glow::RGBA, glow::UNSIGNED_BYTE),
    f(glow::RGBA4, "GL_RGBA4", glow::RGBA, glow::UNSIGNED_BYTE),
    f(glow::RGB5_A1, "GL_RGB5_A1", glow::RGBA, glow::UNSIGNED_BYTE),
    f(
        glow::RGB10_A2,
        "GL_RGB10_A2",
        glow::RGBA,
        glow::UNSIGNED_BYTE,
    ),
    f(glow::RGBA12, "GL_RGBA12", glow::RGBA, glow::UNSIGNED_SHORT),
    f(glow::SRGB8, "GL_SRGB8", glow::RGB, glow::UNSIGNED_BYTE),
    f(
        glow::SRGB8_ALPHA8,
        "GL_SRGB8_ALPHA8",
        glow::RGBA,
        glow::UNSIGNED_BYTE,
    ),
    f(glow::R16, "GL_R16", glow::RED, glow::UNSIGNED_SHORT),
    f(glow::RG16, "GL_RG16", glow::RG, glow::UNSIGNED_SHORT),
    f(glow::RGB16, "GL_RGB16", glow::RGB, glow::UNSIGNED_SHORT),
    f(glow::RGBA16, "GL_RGBA16", glow::RGBA, glow::UNSIGNED_SHORT),
    f(glow::R8_SNORM, "GL_R8_SNORM", glow::RED, glow::BYTE),
    f(glow::RG8_SNORM, "GL_RG8_SNORM", glow::RG, glow::BYTE),
    f(glow::RGB8_SNORM, "GL_RGB8_SNORM", glow::RGB, glow::BYTE),
    f(glow::RGBA8_SNORM, "GL_RGBA8_SNORM", glow::RGBA, glow::BYTE),
    f(glow::R16_SNORM, "GL_R16_SNORM", glow::RED, glow::SHORT),
    f(glow::RG16_SNORM, "GL_RG16_SNORM", glow::RG, glow::SHORT),
    f(glow::RGB16_SNORM, "GL_RGB16_SNORM", glow::RGB, glow::SHORT),
    f(
        glow::RGBA16_SNORM,
        "GL_RGBA16_SNORM",
        glow::RGBA,
        glow::SHORT,
    ),
    f(glow::R16F, "GL_R16F", glow::RED, glow::HALF_FLOAT),
    f(glow::RG16F, "GL_RG16F", glow::RG, glow::HALF_FLOAT),
    f(glow::RGB16F, "GL_RGB16F", glow::RGB, glow::HALF_FLOAT),
    f(glow::RGBA16F, "GL_RGBA16F", glow::RGBA, glow::FLOAT),
    f(glow::R32F, "GL_R32F", glow::RED, glow::FLOAT),
    f(glow::RG32F, "GL_RG32F", glow::RG, glow::FLOAT),
    f(glow::RGB32F, "GL_RGB32F", glow::RGB, glow::FLOAT),
    f(glow::RGBA32F, "GL_RGBA32F", glow::RGBA, glow::FLOAT),
    f(
        glow::R11F_G11F_B10F,
        "GL_R11F_G11F_B10F",
        glow::RGB,
        glow::FLOAT,
    ),
    f(glow::RGB9_E5, "GL_RGB9_E5", glow::RGB, glow::FLOAT),
    f(glow::R8I, "GL_R8I", glow::RED_INTEGER, glow::BYTE),
    f(
        glow::R8UI,
        "GL_R8UI",
        glow::RED_INTEGER,
        glow::UNSIGNED_BYTE,
    ),
    f(glow::R16I, "GL_R16I", glow::RED_INTEGER, glow::SHORT),
    f(
        glow::R16UI,
        "GL_R16UI",
        glow::RED_INTEGER,
        glow::UNSIGNED_SHORT,
    ),
    f(glow::R32I, "GL_R32I", glow::RED_INTEGER, glow::INT),
    f(
        glow::R32UI,
        "GL_R32UI",
        glow::RED_INTEGER,
        glow::UNSIGNED_INT,
    ),
    f(glow::RG8I, "GL_RG8I", glow::RG_INTEGER, glow::BYTE),
    f(
        glow::RG8UI,
        "GL_RG8UI",
        glow::RG_INTEGER,
        glow::UNSIGNED_BYTE,
    ),
    f(glow::RG16I, "GL_RG16I", glow::RG_INTEGER, glow::SHORT),
    f(
        glow::RG16UI,
        "GL_RG16UI",
        glow::RG_INTEGER,
        glow::UNSIGNED_SHORT,
    ),
    f(glow::RG32I, "GL_RG32I", glow::RG_INTEGER, glow::INT),
    f(
        glow::RG32UI,
        "GL_RG32UI",
        glow::RG_INTEGER,
        glow::UNSIGNED_INT,
    ),
    f(glow::RGB8I, "GL_RGB8I", glow::RGB_INTEGER, glow::BYTE),
    f(
        glow::RGB8UI,
        "GL_RGB8UI",
        glow::RGB_INTEGER,
        glow::UNSIGNED_BYTE,
    ),
    f(
        glow::RGB32UI,
        "GL_RGB32UI",
        glow::RGB_INTEGER,
        glow::UNSIGNED_INT,
    ),
    f(glow::RGBA8I, "GL_RGBA8I", glow::RGBA_INTEGER, glow::BYTE),
    f(
        glow::RGBA8UI,
        "GL_RGBA8UI",
        glow::RGBA_INTEGER,
        glow::UNSIGNED_BYTE,
    ),
    f(glow::RGBA16I, "GL_RGBA16I", glow::RGBA_INTEGER, glow::SHORT),
    f(
        glow::RGBA16UI,
        "GL_RGBA16UI",
        glow::RGBA_INTEGER,
        glow::UNSIGNED_SHORT,
    ),
    f(glow::RGBA32I, "GL_RGBA32I", glow::RGBA_INTEGER, glow::INT),
    f(
        glow::RGBA32UI,
        "GL_RGBA32UI",
        glow::RGBA_INTEGER,
        glow::UNSIGNED_INT,
    ),
    f(
        glow::RGB10_A2UI,
        "GL_RGB10_A2UI",
        glow::RGBA_INTEGER,
        glow::UNSIGNED_BYTE,
    ),
];

/// Every depth and depth-stencil internal format, sized and unsized.
pub const DEPTH_FORMATS: &[HostFormat] = &[
    f(
        glow::DEPTH_COMPONENT16,
        "GL_DEPTH_COMPONENT16",
        glow::DEPTH_COMPONENT,
        glow::UNSIGNED_SHORT,
    ),
    f(
        glow::DEPTH_COMPONENT24,
        "GL_DEPTH_COMPONENT24",
        glow::DEPTH_COMPONENT,
        glow::UNSIGNED_INT,
    ),
    f(
        glow::DEPTH_COMPONENT32,
        "GL_DEPTH_COMPONENT32",
        glow::DEPTH_COMPONENT,
        glow::UNSIGNED_INT,
    ),
    f(
        glow::DEPTH_COMPONENT32F,
        "GL_DEPTH_COMPONENT32F",
        glow::DEPTH_COMPONENT,
        glow::FLOAT,
    ),
    f(
        glow::DEPTH_COMPONENT,
        "GL_DEPTH_COMPONENT",
        glow::DEPTH_COMPONENT,
        glow::FLOAT,
    ),
    f(
        glow::DEPTH24_STENCIL8,
        "GL_DEPTH24_STENCIL8",
        glow::DEPTH_STENCIL,
        glow::UNSIGNED_INT_24_8,
    ),
    f(
        glow::DEPTH32F_STENCIL8,
        "GL_DEPTH32F_STENCIL8",
        glow::DEPTH_STENCIL,
        glow::FLOAT_32_UNSIGNED_INT_24_8_REV,
    ),
    f(
        glow::DEPTH_STENCIL,
        "GL_DEPTH_STENCIL",
        glow::DEPTH_STENCIL,
        glow::UNSIGNED_INT_24_8,
    ),
];

/// The stencil-only format a host with no depth may attach.
pub const STENCIL_ONLY: HostFormat = f(
    glow::STENCIL_INDEX8,
    "GL_STENCIL_INDEX8",
    glow::STENCIL_INDEX,
    glow::UNSIGNED_BYTE,
);

impl std::fmt::Debug for HostFormat {
    // A case written out names its formats as the host's code does.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let ty = match self.ty {
            glow::UNSIGNED_BYTE => "GL_UNSIGNED_BYTE",
            glow::BYTE => "GL_BYTE",
            glow::UNSIGNED_SHORT => "GL_UNSIGNED_SHORT",
            glow::SHORT => "GL_SHORT",
            glow::UNSIGNED_INT => "GL_UNSIGNED_INT",
            glow::INT => "GL_INT",
            glow::HALF_FLOAT => "GL_HALF_FLOAT",
            glow::FLOAT => "GL_FLOAT",
            glow::UNSIGNED_INT_24_8 => "GL_UNSIGNED_INT_24_8",
            _ => "GL_FLOAT_32_UNSIGNED_INT_24_8_REV",
        };
        write!(f, "HostFormat::of(\"{}\", \"{ty}\")", self.name)
    }
}

impl HostFormat {
    /// The format named `name` uploaded with pixel type `ty` (both by their
    /// GL names), as a case written out states it.
    pub fn of(name: &str, ty: &str) -> HostFormat {
        COLOR_FORMATS
            .iter()
            .chain(DEPTH_FORMATS)
            .chain([&STENCIL_ONLY])
            .copied()
            .find(|f| f.name == name && format!("{f:?}").contains(&format!("\"{ty}\"")))
            .unwrap_or_else(|| panic!("no host format {name} with type {ty}"))
    }

    /// The format whose GL name is `name` (for regression cases written out
    /// by name); the first entry where a name appears twice (with two types).
    pub fn named(name: &str) -> Option<HostFormat> {
        COLOR_FORMATS
            .iter()
            .chain(DEPTH_FORMATS)
            .chain([&STENCIL_ONLY])
            .copied()
            .find(|f| f.name == name)
    }

    /// A depth-stencil format.
    pub fn has_stencil(&self) -> bool {
        self.pixel == glow::DEPTH_STENCIL || self.pixel == glow::STENCIL_INDEX
    }
}

//! Procedural built-in scenes, each a small, deterministic case of what
//! depth-aware MSAA is about. Sizes are chosen so the models fill a good part
//! of a 16:9 view.
//!
//! | name          | what it exercises |
//! |---------------|-------------------|
//! | `greebles`    | the paper's case: a hull covered in small raised boxes, trenches and thin antennas, lit by coloured point lights close to the surface — averaging positions across depth edges lights the edges wrongly (halos) |
//! | `box`         | a cube on a plane, one directional light: the simplest scene |
//! | `thin`        | wires, rods and sliver triangles against a bright HDR sky: sub-pixel geometry |
//! | `zfight`      | coplanar overlapping panels (z-fighting) and degenerate triangles |
//! | `emissive`    | glowing panels and lamps (HDR emissive up to 300) beside plain models |
//! | `far`         | a detailed model 200 km away through a 0.5° lens with near = 0.01: past FP16 positions and D24 depth |
//! | `transparent` | opaque models behind alpha-blended panes, and an alpha-tested grille |
//! | `hull`        | FreeSpace Open's case: a hull filling the view, covered in detail close to it in depth (plates and seams, painted strips, pipes, low greebles), coloured point lights, dark space |
//! | `halo`        | the paper's Figure 4: point lights just behind a box's edges, a far wall out of their range; averaging positions across the edge lights it |
//! | `lamps`       | the deferred tutorial's picture: boxes lit by a dozen coloured point lights, each light shown as a small bright cube drawn forward after lighting (a blended material), over a dark floor and black sky: forward silhouettes the G-buffer never sees |
//! | `slats`       | thin bright boxes seen at an angle (their side faces sub-pixel slivers) in front of a dark, unlit wall 190 units behind: pixels of three surfaces (front face, side sliver, wall), and in motion a background that barely moves while the slats pass over it |
//! | `bars`        | thin silhouettes: bright slanted bars 1.3 to 3.4 pixels wide at 640x360 in front of a dark far wall, beside a plate of shallow ridges (creases: close in depth, different normals); the scene declares the bars, so the bench measures how wide each method draws them |
//!
//! This module names them and builds one by name; the scenes live in
//! `ship.rs` (`greebles`, `far`), `cases.rs` (one kind of input each) and
//! `claims.rs` (what the bench's claims are measured on), all made with the
//! builders of `tools.rs`.

mod cases;
mod claims;
mod ship;
mod tools;

use super::Scene;
use cases::{box_scene, emissive, lamps, slats, thin, transparent, zfight};
use claims::{bars, halo, hull, ridges};
use ship::{far, greebles};

/// The built-in names, the default first.
pub(crate) const NAMES: &[&str] = &[
    "greebles",
    "box",
    "thin",
    "zfight",
    "emissive",
    "far",
    "transparent",
    "hull",
    "halo",
    "bars",
    "ridges",
    "lamps",
    "slats",
];

/// Builds the built-in scene `name`, or `None` when there is none so named.
pub(crate) fn build(name: &str) -> Option<Scene> {
    let scene = match name {
        "greebles" => greebles(),
        "box" => box_scene(),
        "thin" => thin(),
        "zfight" => zfight(),
        "emissive" => emissive(),
        "far" => far(),
        "transparent" => transparent(),
        "hull" => hull(),
        "halo" => halo(),
        "bars" => bars(),
        "ridges" => ridges(),
        "lamps" => lamps(),
        "slats" => slats(),
        _ => return None,
    };
    Some(scene)
}

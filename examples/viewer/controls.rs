//! The command line, the keys and what each does, and the methods the
//! viewer cycles through.

use std::path::PathBuf;

use winit::event::KeyEvent;
use winit::keyboard::{Key, NamedKey};

/// Frames of a scripted run after which resident memory is the baseline.
pub(crate) const WARMUP_FRAMES: u32 = 100;

/// The methods, in key order (`0` … `5`), as method specs.
pub(crate) const METHODS: [&str; 7] = [
    "none",
    "average",
    "front",
    "median",
    "back",
    "taa",
    "per-sample",
];

/// Resident set size in bytes (Linux; 0 elsewhere).
pub(crate) fn resident_bytes() -> u64 {
    let statm = std::fs::read_to_string("/proc/self/statm").unwrap_or_default();
    let pages: u64 = statm
        .split_whitespace()
        .nth(1)
        .and_then(|p| p.parse().ok())
        .unwrap_or(0);
    pages * 4096
}

/// The command line.
#[derive(Debug)]
pub(crate) struct Args {
    pub(crate) scene: String,
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) samples: u32,
    pub(crate) method: usize,
    pub(crate) layers: u32,
    pub(crate) fxaa: bool,
    pub(crate) smaa: bool,
    pub(crate) frames: Option<u32>,
    pub(crate) screenshot: Option<PathBuf>,
    pub(crate) keys: Vec<char>,
}

/// The command line, as clap reads it.
#[derive(clap::Parser)]
#[command(name = "viewer", about = "The demo renderer in a window, its methods switched live", after_help = KEYS)]
pub(crate) struct Cli {
    /// A built-in scene (`builtin:NAME`) or a glTF file.
    #[arg(default_value = "builtin:greebles")]
    pub(crate) scene: String,
    /// The window's size, WIDTHxHEIGHT.
    #[arg(long, default_value = "960x540", value_parser = parse_size)]
    pub(crate) size: (u32, u32),
    /// Samples per pixel asked for (the driver's real count is used).
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) samples: u32,
    /// The method to start with.
    #[arg(long, default_value = "median", value_parser = METHODS)]
    pub(crate) method: String,
    /// Resolved layers of front, median and back to start with (`T` toggles).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=2))]
    pub(crate) layers: u32,
    /// Start with FXAA on.
    #[arg(long, conflicts_with = "smaa")]
    pub(crate) fxaa: bool,
    /// Start with SMAA 1x on.
    #[arg(long)]
    pub(crate) smaa: bool,
    /// Render this many frames, then quit (1 with --screenshot alone).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) frames: Option<u32>,
    /// Save the last frame's window here.
    #[arg(long)]
    pub(crate) screenshot: Option<PathBuf>,
    /// Keys to press, one a frame, as if typed (see below).
    #[arg(long, default_value = "")]
    pub(crate) keys: String,
}

impl From<Cli> for Args {
    fn from(cli: Cli) -> Args {
        Args {
            scene: cli.scene,
            width: cli.size.0,
            height: cli.size.1,
            samples: cli.samples,
            // clap admitted only the methods' names.
            method: METHODS.iter().position(|m| *m == cli.method).unwrap_or(3),
            layers: cli.layers,
            fxaa: cli.fxaa,
            smaa: cli.smaa,
            frames: cli.frames.or_else(|| cli.screenshot.as_ref().map(|_| 1)),
            screenshot: cli.screenshot,
            keys: cli.keys.chars().collect(),
        }
    }
}

pub(crate) fn parse_size(text: &str) -> Result<(u32, u32), String> {
    text.split_once('x')
        .and_then(|(w, h)| Some((w.parse::<u32>().ok()?, h.parse::<u32>().ok()?)))
        .filter(|&(w, h)| (1..=16384).contains(&w) && (1..=16384).contains(&h))
        .ok_or_else(|| format!("expected WIDTHxHEIGHT such as 960x540, got `{text}`"))
}

/// The keys, for `--help` and `?`.
pub(crate) const KEYS: &str = "keys: M/Shift+M method, 0-6 none/average/front/median/back/taa/per-sample, T second layer, N sample count, F FXAA, S SMAA, \
V/Shift+V view, arrows/HJKL or drag orbit, +/- or wheel zoom, R reset camera, P screenshot, ? keys, Esc/Q quit";

pub(crate) fn print_keys() {
    println!("{KEYS}");
}

/// What a key press or a scripted key does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Action {
    Method(usize),
    StepMethod(isize),
    ToggleLayers,
    NextSamples,
    ToggleFxaa,
    ToggleSmaa,
    StepView(isize),
    Orbit(f32, f32),
    Zoom(f32),
    ResetCamera,
    Screenshot,
    Help,
    Quit,
}

pub(crate) fn action_for_char(c: char) -> Option<Action> {
    const STEP: f32 = 0.15;
    Some(match c {
        'm' => Action::StepMethod(1),
        'M' => Action::StepMethod(-1),
        '0'..='6' => Action::Method(c as usize - '0' as usize),
        't' | 'T' => Action::ToggleLayers,
        'n' | 'N' => Action::NextSamples,
        'f' | 'F' => Action::ToggleFxaa,
        's' | 'S' => Action::ToggleSmaa,
        'v' => Action::StepView(1),
        'V' => Action::StepView(-1),
        'h' | 'H' => Action::Orbit(-STEP, 0.0),
        'l' | 'L' => Action::Orbit(STEP, 0.0),
        'k' | 'K' => Action::Orbit(0.0, STEP),
        'j' | 'J' => Action::Orbit(0.0, -STEP),
        '+' | '=' => Action::Zoom(1.0 / 1.15),
        '-' | '_' => Action::Zoom(1.15),
        'r' | 'R' => Action::ResetCamera,
        'p' | 'P' => Action::Screenshot,
        '?' => Action::Help,
        'q' | 'Q' => Action::Quit,
        _ => return None,
    })
}

pub(crate) fn action_for_key(event: &KeyEvent) -> Option<Action> {
    const STEP: f32 = 0.15;
    match &event.logical_key {
        Key::Named(NamedKey::ArrowLeft) => Some(Action::Orbit(-STEP, 0.0)),
        Key::Named(NamedKey::ArrowRight) => Some(Action::Orbit(STEP, 0.0)),
        Key::Named(NamedKey::ArrowUp) => Some(Action::Orbit(0.0, STEP)),
        Key::Named(NamedKey::ArrowDown) => Some(Action::Orbit(0.0, -STEP)),
        Key::Named(NamedKey::PageUp) => Some(Action::Zoom(1.0 / 1.15)),
        Key::Named(NamedKey::PageDown) => Some(Action::Zoom(1.15)),
        Key::Named(NamedKey::Escape) => Some(Action::Quit),
        Key::Character(text) => text.chars().next().and_then(action_for_char),
        _ => None,
    }
}

//! A plan as `render --explain` prints it: text, or JSON.

use super::Plan;
use crate::gbuffer::fmt_bytes;
use crate::renderer::options::AaMode;

impl Plan {
    /// The plan as JSON (`render --explain --json`; keys as docs/plan.md lists them).
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "scene": self.scene,
            "width": self.width,
            "height": self.height,
            "method": self.aa.name(),
            "requested_method": self.requested_aa.name(),
            "samples": self.samples,
            "requested_samples": self.requested_samples,
            "adaptive": self.adaptive,
            "attachments": self.attachments.iter().map(|a| serde_json::json!({
                "name": a.name,
                "format": a.format.name(),
                "multisampled": a.multisampled,
            })).collect::<Vec<_>>(),
            "passes": self.passes.iter().map(|p| p.name()).collect::<Vec<_>>(),
            "left_out": self.left_out,
            "kept": self.kept,
            "constant_specular": self.constant_specular,
            "permutations": self.permutations,
            "gbuffer_bytes": self.gbuffer_bytes,
            "full_gbuffer_bytes": self.full_gbuffer_bytes,
            "second_layer_bytes": self.second_layer_bytes,
            "budget_bytes": self.budget_bytes,
            "budget_source": self.budget_source,
            "warnings": self.warnings,
        })
    }

    /// The plan in words (`render --explain`).
    pub fn to_text(&self) -> String {
        use std::fmt::Write;
        let mut t = String::new();
        let method = if self.aa == self.requested_aa {
            self.aa.name().to_string()
        } else {
            format!("{} (asked: {})", self.aa.name(), self.requested_aa.name())
        };
        let _ = writeln!(
            t,
            "plan for `{}` at {}x{}, {method}, {}x{}",
            self.scene,
            self.width,
            self.height,
            self.samples,
            if self.adaptive { "" } else { ", full layout" }
        );
        let _ = writeln!(t, "attachments:");
        for a in &self.attachments {
            let _ = writeln!(
                t,
                "  {:<10} {:<20} {}",
                a.name,
                a.format.name(),
                if a.multisampled {
                    format!("multisampled {}x", self.samples)
                } else {
                    "single-sample".into()
                }
            );
        }
        let names: Vec<&str> = self.passes.iter().map(|p| p.name()).collect();
        let _ = writeln!(t, "passes: {}", names.join(" → "));
        if !self.left_out.is_empty() {
            let _ = writeln!(t, "left out:");
            for l in &self.left_out {
                let _ = writeln!(t, "  {}: {}", l.name, l.why);
            }
        }
        if !self.kept.is_empty() {
            let _ = writeln!(t, "kept:");
            for l in &self.kept {
                let _ = writeln!(t, "  {}: {}", l.name, l.why);
            }
        }
        let _ = writeln!(t, "shaders:");
        for p in &self.permutations {
            let _ = writeln!(
                t,
                "  {}: {}",
                p.program,
                if p.defines.is_empty() {
                    "(no defines)".to_string()
                } else {
                    p.defines.join(" ")
                }
            );
        }
        let _ = writeln!(
            t,
            "G-buffer: {} ({:.0}% of FreeSpace Open's layout at this size and count, {}); budget {} ({})",
            fmt_bytes(self.gbuffer_bytes),
            100.0 * self.gbuffer_bytes as f64 / self.full_gbuffer_bytes.max(1) as f64,
            fmt_bytes(self.full_gbuffer_bytes),
            fmt_bytes(self.budget_bytes),
            self.budget_source
        );
        if let (AaMode::Resolve(settings), true) = (self.aa, self.second_layer_bytes > 0) {
            let _ = writeln!(
                t,
                "second layer: {} of it (its G-buffer and the first layer's copy, coverage, depth, selection, two lit copies, the stencil mask); clusters split by depth window and by normal (cosine below {})",
                fmt_bytes(self.second_layer_bytes),
                settings.normal_threshold
            );
        }
        for w in &self.warnings {
            let _ = writeln!(t, "warning: {w}");
        }
        t
    }
}

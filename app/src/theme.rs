//! The HMI palette (ISA-101 high-performance style), loaded from `assets/palette.ron`.
//!
//! Normal equipment is drawn in greys on a grey background; colour is reserved for
//! abnormal states: red for trips, violated elements and damaged boxes, amber for alarms
//! and actuators the filter forces.

use egui::Color32;
use serde::Deserialize;

/// DejaVu Sans, the fallback font for the glyphs egui's default font lacks (arrows,
/// the combining overbar of the paper's notation).
pub const FALLBACK_FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// Installs the fallback font and the palette's visuals; call once on a new context.
pub fn setup_context(ctx: &egui::Context, palette: &Palette) {
    use egui::epaint::text::{FontInsert, FontPriority, InsertFontFamily};
    ctx.add_font(FontInsert::new(
        "DejaVuSans",
        egui::FontData::from_static(FALLBACK_FONT),
        vec![
            InsertFontFamily {
                family: egui::FontFamily::Proportional,
                priority: FontPriority::Lowest,
            },
            InsertFontFamily {
                family: egui::FontFamily::Monospace,
                priority: FontPriority::Lowest,
            },
        ],
    ));
    palette.apply(ctx);
}

/// The palette file's text, compiled in.
pub const DEFAULT_PALETTE: &str = include_str!("../../assets/palette.ron");

#[derive(Deserialize)]
#[serde(rename = "Palette")]
struct PaletteFile {
    background: [u8; 3],
    panel: [u8; 3],
    floor: [u8; 3],
    equipment: [u8; 3],
    equipment_edge: [u8; 3],
    running: [u8; 3],
    text: [u8; 3],
    text_dim: [u8; 3],
    sensor_off: [u8; 3],
    sensor_on: [u8; 3],
    box_small: [u8; 3],
    box_large: [u8; 3],
    box_edge: [u8; 3],
    trip: [u8; 3],
    alarm: [u8; 3],
    forced: [u8; 3],
    ghost: [u8; 3],
    highlight: [u8; 3],
    caution: [u8; 3],
    normal: [u8; 3],
}

/// Colours of the console.
#[derive(Clone, Debug, PartialEq)]
pub struct Palette {
    /// Window background.
    pub background: Color32,
    /// Side panels.
    pub panel: Color32,
    /// Synoptic floor.
    pub floor: Color32,
    /// Idle equipment.
    pub equipment: Color32,
    /// Equipment outlines.
    pub equipment_edge: Color32,
    /// Running equipment (darker grey, still no colour).
    pub running: Color32,
    /// Text.
    pub text: Color32,
    /// Secondary text.
    pub text_dim: Color32,
    /// Sensor lamp off.
    pub sensor_off: Color32,
    /// Sensor lamp on.
    pub sensor_on: Color32,
    /// Small box.
    pub box_small: Color32,
    /// Large box.
    pub box_large: Color32,
    /// Box outline.
    pub box_edge: Color32,
    /// Trip, violated element, damaged box.
    pub trip: Color32,
    /// Alarm.
    pub alarm: Color32,
    /// Actuator forced by the filter.
    pub forced: Color32,
    /// Projection (level 1) ghosts.
    pub ghost: Color32,
    /// Explanation marks that are not abnormal (changes, expected actions).
    pub highlight: Color32,
    /// Third alarm priority (medium), and the degraded state.
    pub caution: Color32,
    /// The plant producing normally (the state indicator only).
    pub normal: Color32,
}

fn c([r, g, b]: [u8; 3]) -> Color32 {
    Color32::from_rgb(r, g, b)
}

impl Palette {
    /// Parses a palette file.
    pub fn from_ron(text: &str) -> Result<Self, String> {
        let f: PaletteFile = ron::from_str(text).map_err(|e| e.to_string())?;
        Ok(Self {
            background: c(f.background),
            panel: c(f.panel),
            floor: c(f.floor),
            equipment: c(f.equipment),
            equipment_edge: c(f.equipment_edge),
            running: c(f.running),
            text: c(f.text),
            text_dim: c(f.text_dim),
            sensor_off: c(f.sensor_off),
            sensor_on: c(f.sensor_on),
            box_small: c(f.box_small),
            box_large: c(f.box_large),
            box_edge: c(f.box_edge),
            trip: c(f.trip),
            alarm: c(f.alarm),
            forced: c(f.forced),
            ghost: c(f.ghost),
            highlight: c(f.highlight),
            caution: c(f.caution),
            normal: c(f.normal),
        })
    }

    /// Applies the palette to egui's visuals (light, grey).
    pub fn apply(&self, ctx: &egui::Context) {
        let mut v = egui::Visuals::light();
        v.panel_fill = self.panel;
        v.window_fill = self.panel;
        v.extreme_bg_color = self.background;
        v.override_text_color = Some(self.text);
        v.selection.bg_fill = Color32::from_rgb(150, 160, 175);
        v.selection.stroke.color = self.text;
        ctx.set_visuals(v);
    }
}

impl Default for Palette {
    fn default() -> Self {
        match Self::from_ron(DEFAULT_PALETTE) {
            Ok(p) => p,
            Err(e) => {
                tracing::warn!("built-in palette unreadable: {e}");
                let g = Color32::GRAY;
                Self {
                    background: g,
                    panel: g,
                    floor: g,
                    equipment: g,
                    equipment_edge: Color32::DARK_GRAY,
                    running: Color32::DARK_GRAY,
                    text: Color32::BLACK,
                    text_dim: Color32::DARK_GRAY,
                    sensor_off: g,
                    sensor_on: Color32::WHITE,
                    box_small: Color32::LIGHT_GRAY,
                    box_large: g,
                    box_edge: Color32::BLACK,
                    trip: Color32::RED,
                    alarm: Color32::ORANGE,
                    forced: Color32::ORANGE,
                    ghost: Color32::BLUE,
                    highlight: Color32::BLUE,
                    caution: Color32::YELLOW,
                    normal: Color32::DARK_GREEN,
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn built_in_palette_parses() {
        assert!(super::Palette::from_ron(super::DEFAULT_PALETTE).is_ok());
    }
}

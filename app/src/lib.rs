//! The Vigie operator console (egui): a thin shell over the core's state.
//!
//! - [`console::Console`] is the `eframe::App`: `logic` advances the simulation by real
//!   time × speed, `ui` renders the synoptic, the explanation levels, alarms, journal,
//!   chronogram and the maintenance and training views;
//! - [`live`] is the Modbus TCP link (monitor, gateway, emulator server), which the
//!   console can follow (`vigie --link CONFIG`) and `vigie gateway` runs headless;
//! - [`theme`] holds the palette (`assets/palette.ron`);
//! - [`bench_frames`] measures the CPU time of a frame without a GPU.

pub mod console;
pub mod historian;
pub mod i18n;
pub mod live;
pub mod theme;

pub use console::{Command, Console, ConsoleOptions, Mode};

use std::time::Instant;

/// The application icon (`assets/icon.png`).
pub const ICON_PNG: &[u8] = include_bytes!("../../assets/icon.png");

/// Decodes the icon for the window.
pub fn icon() -> Option<egui::IconData> {
    let img = image::load_from_memory(ICON_PNG).ok()?.into_rgba8();
    let (width, height) = img.dimensions();
    Some(egui::IconData {
        rgba: img.into_raw(),
        width,
        height,
    })
}

/// Opens the console window and runs it until closed.
pub fn run_console(opts: &ConsoleOptions) -> anyhow::Result<()> {
    let mut console =
        Console::new(opts).map_err(|e| anyhow::anyhow!("cannot open the console:\n{e}"))?;
    let mut viewport = egui::ViewportBuilder::default()
        .with_title("Vigie — operator console")
        .with_inner_size([1600.0, 1000.0])
        .with_min_inner_size([900.0, 600.0]);
    if let Some(icon) = icon() {
        viewport = viewport.with_icon(std::sync::Arc::new(icon));
    }
    let native = eframe::NativeOptions {
        viewport,
        ..Default::default()
    };
    eframe::run_native(
        "vigie",
        native,
        Box::new(move |cc| {
            console.setup(&cc.egui_ctx);
            Ok(Box::new(console))
        }),
    )
    .map_err(|e| anyhow::anyhow!("console: {e}"))
}

/// Result of [`bench_frames`].
#[derive(Clone, Debug, PartialEq)]
pub struct FrameBench {
    /// Frames measured.
    pub frames: usize,
    /// Median CPU time of one frame (logic + ui + tessellation), ms.
    pub median_ms: f64,
    /// 95th percentile, ms.
    pub p95_ms: f64,
    /// Simulated time covered by the memory run, s.
    pub memory_sim_s: u64,
    /// Resident memory after the warm-up (first simulated 10 minutes), KiB (0 if unknown).
    pub rss_warm_kib: u64,
    /// Resident memory at the end, KiB (0 if unknown).
    pub rss_end_kib: u64,
}

fn rss_kib() -> u64 {
    std::fs::read_to_string("/proc/self/statm")
        .ok()
        .and_then(|s| {
            s.split_whitespace()
                .nth(1)
                .and_then(|v| v.parse::<u64>().ok())
        })
        .map_or(0, |pages| pages * 4)
}

fn run_frame(ctx: &egui::Context, console: &mut Console, t: f64, size: egui::Vec2) {
    let input = egui::RawInput {
        screen_rect: Some(egui::Rect::from_min_size(egui::Pos2::ZERO, size)),
        time: Some(t),
        ..Default::default()
    };
    let mut out = ctx.run_ui(input, |ui| {
        console.logic(ui.ctx());
        console.ui(ui);
    });
    // No GPU: the texture updates are dropped on purpose.
    out.textures_delta.clear();
    let prims = ctx.tessellate(out.shapes, out.pixels_per_point);
    std::hint::black_box(prims);
}

/// Runs `frames` frames of the console on `opts` at 60 frames/s and 1x through a
/// headless egui context (no GPU) and returns the median CPU time per frame; then, when
/// `memory_hour` is set, runs one simulated hour at 100x (frames of 1/60 s) and reports
/// the resident memory after the first 10 simulated minutes and at the end.
pub fn bench_frames(
    opts: &ConsoleOptions,
    frames: usize,
    memory_hour: bool,
) -> anyhow::Result<FrameBench> {
    let mut opts = opts.clone();
    opts.data_dir = None;
    opts.paused = false;
    opts.speed = 1.0;
    let mut console = Console::new(&opts).map_err(|e| anyhow::anyhow!("{e}"))?;
    console.apply(Command::Plant(vigie_core::sim::OperatorAction::Start));
    let ctx = egui::Context::default();
    console.setup(&ctx);
    let size = egui::vec2(1600.0, 1000.0);
    let dt = 1.0 / 60.0;
    let mut t = 0.0;
    for _ in 0..30 {
        run_frame(&ctx, &mut console, t, size);
        t += dt;
    }
    let mut samples = Vec::with_capacity(frames);
    for _ in 0..frames.max(1) {
        let start = Instant::now();
        run_frame(&ctx, &mut console, t, size);
        samples.push(start.elapsed().as_secs_f64() * 1000.0);
        t += dt;
    }
    samples.sort_by(f64::total_cmp);
    let median_ms = samples[samples.len() / 2];
    #[allow(
        clippy::cast_possible_truncation,
        clippy::cast_sign_loss,
        clippy::cast_precision_loss
    )]
    let p95_ms = samples[((samples.len() as f64 * 0.95) as usize).min(samples.len() - 1)];
    let (mut warm, mut end, mut sim_s) = (0, 0, 0);
    if memory_hour {
        console.apply(Command::SetSpeed(100.0));
        let start_sim = console.sim.now().0;
        let mut warmed = false;
        while console.sim.now().0 < start_sim + 3_600_000 {
            run_frame(&ctx, &mut console, t, size);
            t += dt;
            if !warmed && console.sim.now().0 >= start_sim + 600_000 {
                warm = rss_kib();
                warmed = true;
            }
        }
        end = rss_kib();
        sim_s = (console.sim.now().0 - start_sim) / 1000;
    }
    Ok(FrameBench {
        frames: samples.len(),
        median_ms,
        p95_ms,
        memory_sim_s: sim_s,
        rss_warm_kib: warm,
        rss_end_kib: end,
    })
}

//! The command line's arguments (clap definitions) and their translation into run
//! options. A module of the binary, not of the library.

use std::path::PathBuf;

use clap::{Parser, Subcommand};

use splatter::farm::{self, FarmError};
use splatter::gpu::BackendChoice;
use splatter::run::{Input, RunOptions};
use splatter::scene;

#[derive(Parser)]
#[command(
    name = "splatter",
    version,
    about = "Simulate and render 3D Gaussian Splatting scenes to PNG frames."
)]
pub(crate) struct Cli {
    /// Force a graphics API instead of choosing the best adapter.
    #[arg(long, global = true, value_enum)]
    pub(crate) backend: Option<BackendChoice>,
    #[command(subcommand)]
    pub(crate) command: Option<Command>,
}

#[derive(Subcommand)]
pub(crate) enum Command {
    /// Render a scene file (or, with --ply, a PLY file) to DIR/frame_00000.png, …
    /// Without a scene and without --ply, renders the embedded default scene.
    Render(Box<RenderArgs>),
    /// Describe a splat file of any format: counts, robust bounds, floaters, opacity and
    /// scale, the estimated up axis and support, and the transform that stands it upright.
    Inspect {
        /// The capture (PLY, compressed.ply, .splat, .spz, SOG folder or .sog, .glb/.gltf).
        file: PathBuf,
        /// Height of the support in the suggested transform.
        #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
        support_height: f32,
        /// Also render an overview of the upright capture over a labelled ground grid.
        #[arg(long, value_name = "FILE.png")]
        preview: Option<PathBuf>,
        /// The capture's cameras (an INRIA cameras.json, a COLMAP model, a transforms.json or
        /// a nerfstudio camera_path.json): up is the mean of its cameras' up vectors.
        /// Default: a cameras.json next to the capture, when there is one.
        #[arg(long, value_name = "FILE")]
        cameras: Option<PathBuf>,
    },
    /// Convert a splat file of any format we read (PLY, compressed.ply, SPZ, SOG, .splat,
    /// glTF/GLB) into one we write, chosen by OUT's extension: .ply, .spz, .splat or .glb
    /// (docs/formats.md). Prints one line: counts, formats, size, what was dropped.
    Convert {
        /// The file to read (or a SOG folder).
        input: PathBuf,
        /// The file to write (replaced atomically if it exists).
        output: PathBuf,
        /// SPZ version to write for a .spz output (3: gzip, read by every SPZ reader; 4:
        /// zstd per stream).
        #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(3..=4))]
        spz_version: u32,
    },
    /// Count the pieces of particle point clouds (PLY with x, y, z: `render
    /// --export-particles` files or another solver's): particles closer than the link
    /// distance are linked (unless a `damage` property says one is broken through: such
    /// rubble links nothing), linked particles form a fragment, and a fragment of at least
    /// 1% of the particles is a piece. One line per file and object.
    Fragments {
        /// The particle files.
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// Link distance (default: the file's `comment dx`, the grid spacing).
        #[arg(long)]
        link: Option<f64>,
    },
    /// List the GPU adapters, their optional features and limits.
    Info,
    /// Print the JSON Schema of scene files.
    Schema,
    /// Print the embedded default scene (a starting point for your own).
    DefaultScene,
    /// Benchmarks (see docs/performance.md).
    Bench {
        #[command(subcommand)]
        what: BenchWhat,
    },
}

#[derive(Subcommand)]
pub(crate) enum BenchWhat {
    /// Nanoseconds per particle-step of the GPU MPM step (NACC): 20k particles on a 64³
    /// grid and 1M particles on a 128³ grid.
    Sim {
        /// Steps timed per case (after one warm-up step).
        #[arg(long, default_value_t = 20)]
        steps: u32,
        /// Only the 20k case.
        #[arg(long)]
        quick: bool,
        /// Also break each case down by pass (each pass run alone and waited for).
        #[arg(long)]
        per_pass: bool,
        /// Step the NACC cases with two-field separation (`"separation": "damage_gradient"`),
        /// on the gather path, the only one that runs it.
        #[arg(long)]
        separation: bool,
        /// Instead, step one NACC case of about this many particles (a cube, 8 per cell, on
        /// a grid sized to hold it): arrays past one storage binding run page by page; wall
        /// time, bytes per particle, peak memory and the adapter's largest size.
        #[arg(long, conflicts_with_all = ["quick", "per_pass", "separation"])]
        particles: Option<usize>,
    },
    /// Milliseconds per frame of the renderer: render passes, readback, PNG encoding.
    Render {
        /// Repetitions per case (the median is reported).
        #[arg(long, default_value_t = 5)]
        repeat: usize,
        /// Only the small cases (100k Gaussians), for a quick check.
        #[arg(long)]
        quick: bool,
        /// Also break each case down by pass (one extra frame, each pass waited for).
        #[arg(long)]
        per_pass: bool,
        /// Instead, render one 1920×1080 frame of this many synthetic SH-3 Gaussians: arrays
        /// past one storage binding run page by page; wall time, bytes per Gaussian, peak
        /// memory and the adapter's largest size.
        #[arg(long, conflicts_with_all = ["quick", "per_pass"])]
        gaussians: Option<usize>,
    },
    /// Moved to the lab: runs `splatter-lab suite` with the same arguments.
    #[command(hide = true, disable_help_flag = true)]
    Suite {
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<String>,
    },
    /// Moved to the lab: runs `splatter-lab accuracy` with the same arguments.
    #[command(hide = true, disable_help_flag = true)]
    Accuracy {
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<String>,
    },
    /// Seconds to read splat files of any format (the file is read from the page cache:
    /// decoding, not the disk, is measured).
    Read {
        /// The files (or SOG folders).
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// Repetitions per file (the median is reported).
        #[arg(long, default_value_t = 5)]
        repeat: usize,
    },
}

/// `--p2g`: a P2G path by name.
#[derive(Clone, Copy, clap::ValueEnum)]
pub(crate) enum P2gArg {
    Gather,
    Atomic,
    Fixed,
}

impl P2gArg {
    pub(crate) fn path(self) -> splatter::sim::gpu::P2gPath {
        use splatter::sim::gpu::P2gPath;
        match self {
            P2gArg::Gather => P2gPath::Gather,
            P2gArg::Atomic => P2gPath::Atomic,
            P2gArg::Fixed => P2gPath::Fixed,
        }
    }
}

/// `--passes`: a pass by name.
#[derive(Clone, Copy, clap::ValueEnum)]
pub(crate) enum PassArg {
    Alpha,
    Depth,
    Normal,
    Id,
}

impl PassArg {
    pub(crate) fn pass(self) -> splatter::output::passes::Pass {
        use splatter::output::passes::Pass;
        match self {
            PassArg::Alpha => Pass::Alpha,
            PassArg::Depth => Pass::Depth,
            PassArg::Normal => Pass::Normal,
            PassArg::Id => Pass::Id,
        }
    }
}

#[derive(clap::Args)]
pub(crate) struct RenderArgs {
    /// Scene file (JSON). See docs/scene-format.md.
    pub(crate) scene: Option<PathBuf>,
    /// Output directory (overrides the scene's `output.dir`).
    #[arg(long)]
    pub(crate) out: Option<PathBuf>,
    /// Frames to render: `A..B` (B exclusive), `A..`, `..B`, a single frame `A`, or a
    /// render manager's frame list of inclusive ranges (Deadline, Open Job Description):
    /// `1-10`, `1-3,5,7-20:2`, `20-0:-5`. Only the frames named are written; a simulated
    /// scene still simulates every frame up to the last one named.
    #[arg(long, value_name = "SPEC", allow_hyphen_values = true)]
    pub(crate) frames: Option<String>,
    /// Render one farm task's share of the frames: chunk I (0-based) of N consecutive
    /// frames of the sorted frame set, I from --task-index, else SLURM_ARRAY_TASK_ID, else
    /// JOB_COMPLETION_INDEX. A task past the last chunk renders nothing and exits 0.
    #[arg(long, value_name = "N")]
    pub(crate) chunk: Option<u32>,
    /// With --chunk: this task's 0-based chunk index (instead of the environment's).
    #[arg(long, value_name = "I", requires = "chunk")]
    pub(crate) task_index: Option<u32>,
    /// Image width in pixels (overrides the scene's).
    #[arg(long)]
    pub(crate) width: Option<u32>,
    /// Image height in pixels (overrides the scene's).
    #[arg(long)]
    pub(crate) height: Option<u32>,
    /// Resolution in space and on screen: `draft` (twice as coarse), `standard` (the
    /// scene as written) or `high` (twice as fine: 8× the particles, twice the image
    /// size; meant for a GPU). --width/--height still win for the image size.
    #[arg(long, value_enum, default_value_t = scene::quality::Quality::Standard)]
    pub(crate) quality: scene::quality::Quality,
    /// Also write each rendered frame's Gaussians (deformed, SH rotated into the world
    /// frame) as a standard 3DGS PLY: DIR/frame_00000.ply, …
    #[arg(long, value_name = "DIR")]
    pub(crate) export_ply: Option<PathBuf>,
    /// Also write each rendered frame's Gaussians as SPZ (version 3, gzip; an order of
    /// magnitude smaller than PLY, opened by web viewers): DIR/frame_00000.spz, …
    #[arg(long, value_name = "DIR")]
    pub(crate) export_spz: Option<PathBuf>,
    /// Also write each rendered frame's Gaussians as glTF 2.0 GLB with
    /// KHR_gaussian_splatting (the z-up world turned into glTF's y-up; region labels as the
    /// attribute _SPLATTER_LABEL): DIR/frame_00000.glb, …
    #[arg(long, value_name = "DIR")]
    pub(crate) export_glb: Option<PathBuf>,
    /// Also write each rendered frame's MPM particles (position, velocity, mass, volume,
    /// NACC hardening state log Jᴾ, material, object) as a binary PLY point cloud:
    /// DIR/frame_00000.ply, … (docs/formats.md, "Particle files"; `splatter fragments`
    /// counts their pieces).
    #[arg(long, value_name = "DIR")]
    pub(crate) export_particles: Option<PathBuf>,
    /// Also write the rendered frames' cameras: DIR/cameras.json (INRIA 3DGS, read back by
    /// a `cameras_json` path or `--cameras`) and DIR/camera_path.json (a nerfstudio render
    /// path), to match a plate in Blender or nerfstudio (docs/scene-format.md).
    #[arg(long, value_name = "DIR")]
    pub(crate) export_cameras: Option<PathBuf>,
    /// Also write passes beside each frame, from the same compositing: `alpha`
    /// (OUT/alpha/frame_00000.png, RGBA with straight colour), `depth`
    /// (OUT/depth/frame_00000.exr, one float channel Z: the alpha-weighted mean camera-space
    /// depth, +inf where nothing was drawn), `normal` (OUT/normal/frame_00000.exr, channels
    /// R, G, B: the alpha-weighted camera-space normal, x right, y down, z forward) and `id`
    /// (OUT/id/frame_00000.png, 16-bit grey: the id of the object and region that
    /// contributes most, named in the manifest's `ids`). A comma-separated list
    /// (docs/scene-format.md).
    #[arg(long, value_delimiter = ',', value_name = "PASS")]
    pub(crate) passes: Vec<PassArg>,
    /// Quick look at a capture (any splat format) without a scene file: stood upright
    /// and orbited, framing its robust bounds.
    #[arg(long, conflicts_with = "scene")]
    pub(crate) ply: Option<PathBuf>,
    /// With --ply: a camera file to take the camera from: an INRIA 3DGS cameras.json, a
    /// COLMAP model (its folder, e.g. sparse/0, or a file of it), a transforms.json or a
    /// nerfstudio camera_path.json, told by its content. The capture is then drawn
    /// untouched, in its own frame, where those cameras were posed.
    #[arg(long, requires = "ply")]
    pub(crate) cameras: Option<PathBuf>,
    /// With --cameras: index of the camera in the file (default 0; COLMAP images in the
    /// order of their names).
    #[arg(long, requires = "cameras")]
    pub(crate) camera: Option<usize>,
    /// With --cameras of a nerfstudio camera_path.json: the training run's
    /// dataparser_transforms.json, which maps the path from nerfstudio's normalised world
    /// back into the capture's frame (as nerfstudio's own exporter does).
    #[arg(long, requires = "cameras", value_name = "FILE")]
    pub(crate) dataparser: Option<PathBuf>,
    /// With --ply: which way is up in the capture (an axis: +x, -x, +y, -y, +z, -z), instead
    /// of the estimate (docs/captures.md, The up axis).
    #[arg(
        long,
        requires = "ply",
        conflicts_with = "cameras",
        value_name = "AXIS",
        allow_hyphen_values = true
    )]
    pub(crate) up: Option<String>,
    /// Continue a killed or failed run in the same output directory: frames already
    /// written are skipped, and a simulation restarts from OUT_DIR/checkpoint.bin (a
    /// checkpoint of another scene, mode or program version is refused).
    #[arg(long)]
    pub(crate) resume: bool,
    /// Bit-identical frames for the same input on the same adapter: the simulation sums
    /// P2G in integers (fixed point) or in a fixed order (the sorted gather: with two-field
    /// separation, and on CPU drivers), instead of with float atomics. (On a CPU driver a
    /// long run without it may take the gather too, where it measures faster: the log says.)
    #[arg(long)]
    pub(crate) deterministic: bool,
    /// Run the simulation's P2G on this path instead of the one chosen for the adapter
    /// (to reproduce a failure on every path, or to compare them): `gather` (sorted, in a
    /// fixed order; every adapter), `atomic` (float atomics; needs them, not with
    /// --deterministic), `fixed` (fixed-point integer atomics, deterministic)
    #[arg(long, value_name = "PATH")]
    pub(crate) p2g: Option<P2gArg>,
    /// Save the simulation state to OUT_DIR/checkpoint.bin every N frames (0: never).
    #[arg(long, value_name = "N", default_value_t = 10)]
    pub(crate) checkpoint_every: u32,
    /// Render-only: take each frame's Gaussians from DIR/frame_NNNNN.ply (as written by
    /// --export-ply) instead of building and simulating the scene; the scene gives the
    /// camera path and output settings. For splitting frame ranges over machines.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["ply", "export_ply", "export_spz", "export_glb", "export_particles"])]
    pub(crate) from_states: Option<PathBuf>,
    /// After rendering, assemble the frames into a video with ffmpeg (which must be on
    /// the PATH; checked before rendering starts).
    #[arg(long, value_name = "FILE")]
    pub(crate) video: Option<PathBuf>,
    /// Count the pieces each simulated object has broken into, every rendered frame:
    /// particles closer than Δx and not broken through are linked, linked particles form a
    /// fragment (OUT_DIR/fragments.csv, docs/physics.md; the last frame's counts are
    /// printed).
    #[arg(long, conflicts_with_all = ["ply", "from_states"])]
    pub(crate) fragments: bool,
}

impl RenderArgs {
    /// The run's options; the chunk's task index may come from the environment.
    pub(crate) fn into_options(self) -> Result<RunOptions, FarmError> {
        let env = |name: &str| std::env::var(name).ok();
        let chunk = self
            .chunk
            .map(|size| farm::chunk(size, self.task_index, &env))
            .transpose()?;
        let input = match (self.from_states, self.ply) {
            (Some(dir), _) => Input::States {
                scene: self.scene,
                dir,
            },
            (None, Some(file)) => Input::Ply {
                file,
                cameras: self.cameras,
                dataparser: self.dataparser,
                camera: self.camera,
                up: self.up,
            },
            (None, None) => Input::Scene(self.scene),
        };
        Ok(RunOptions {
            input,
            out: self.out,
            frames: self.frames,
            chunk,
            width: self.width,
            height: self.height,
            quality: self.quality,
            export_ply: self.export_ply,
            export_spz: self.export_spz,
            export_glb: self.export_glb,
            export_particles: self.export_particles,
            export_cameras: self.export_cameras,
            passes: self.passes.iter().map(|p| p.pass()).collect(),
            resume: self.resume,
            deterministic: self.deterministic,
            p2g: self.p2g.map(P2gArg::path),
            checkpoint_every: self.checkpoint_every,
            video: self.video,
            fragments: self.fragments,
        })
    }
}

//! Peers of `splatter-lab peer`: other MPM codes stepped on the same case in the same run,
//! each through its program in `benches/peers/` (a Python script, or a standalone cargo
//! project built beforehand). Each takes the same arguments and prints a line starting
//! with its name and a last line `ms/step: <value>`.

use anyhow::Result;

use splatter::bench::SimCase;

/// Another MPM code that `splatter-lab peer` runs on the same case in the same run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Peer {
    /// Taichi on the CPU (`benches/peers/taichi_mpm.py`; `pip install taichi==1.7.4`).
    Taichi,
    /// dimforge's slosh on the same wgpu adapter (`benches/peers/slosh/`, built
    /// beforehand as its README says; the binary from `SLOSH_PEER`, else
    /// `benches/peers/slosh/target/release/slosh-peer`).
    Slosh,
}

/// What a peer printed: its description line, its milliseconds per step, and its
/// per-pass lines (`pass NAME: MS ms/step`) when it times passes.
pub struct PeerRun {
    pub line: String,
    pub ms: f64,
    pub passes: Vec<String>,
}

impl Peer {
    pub fn name(self) -> &'static str {
        match self {
            Peer::Taichi => "taichi",
            Peer::Slosh => "slosh",
        }
    }

    /// The peer's program, next to the sources this program was built from (or, for
    /// slosh, where `SLOSH_PEER` says), and how to get it when it is missing.
    fn program(self) -> (std::path::PathBuf, &'static str) {
        let sources = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        match self {
            Peer::Taichi => (
                sources.join("benches/peers/taichi_mpm.py"),
                "it ships with the sources",
            ),
            Peer::Slosh => (
                std::env::var_os("SLOSH_PEER").map_or_else(
                    || sources.join("benches/peers/slosh/target/release/slosh-peer"),
                    std::path::PathBuf::from,
                ),
                "build it as benches/peers/slosh/README.md says, or set SLOSH_PEER to the binary",
            ),
        }
    }

    /// The command that runs the peer's program.
    fn command(self, program: &std::path::Path) -> std::process::Command {
        match self {
            Peer::Taichi => {
                let mut c = std::process::Command::new("python3");
                c.arg(program);
                c
            }
            Peer::Slosh => std::process::Command::new(program),
        }
    }

    /// What to install when the peer fails.
    fn needs(self) -> &'static str {
        match self {
            Peer::Taichi => "pip install taichi==1.7.4",
            Peer::Slosh => "see benches/peers/slosh/README.md",
        }
    }

    /// The peer's program, or an error saying how to get it (checked before our own cases
    /// run, so that a missing peer costs no minutes).
    pub fn check(self) -> Result<std::path::PathBuf> {
        let (script, how) = self.program();
        if !script.is_file() {
            anyhow::bail!(
                "peer {}: {} not found ({how})",
                self.name(),
                script.display()
            );
        }
        Ok(script)
    }

    /// Step `case` (a fixed-corotated cube) `steps` times in the peer.
    pub fn run(self, case: &SimCase, steps: u32) -> Result<PeerRun> {
        let script = self.check()?;
        let p = &case.particles;
        let per_axis = (p.len() as f64).cbrt().round() as usize;
        let spacing = case.grid.dx / 2.0;
        let lo = p.x[0] - glam::DVec3::splat(spacing / 2.0);
        let (e, nu) = (SimCase::E, SimCase::NU);
        let args: Vec<String> = [
            "--per-axis".into(),
            per_axis.to_string(),
            "--cells".into(),
            case.cells.to_string(),
            "--lo".into(),
            lo.x.to_string(),
            lo.y.to_string(),
            lo.z.to_string(),
            "--dt".into(),
            case.params.dt.to_string(),
            "--steps".into(),
            steps.to_string(),
            "--E".into(),
            e.to_string(),
            "--nu".into(),
            nu.to_string(),
            "--density".into(),
            SimCase::DENSITY.to_string(),
        ]
        .into();
        let output = self.command(&script).args(&args).output().map_err(|e| {
            anyhow::anyhow!("peer {}: cannot run {}: {e}", self.name(), script.display())
        })?;
        let stdout = String::from_utf8_lossy(&output.stdout);
        let stderr = String::from_utf8_lossy(&output.stderr);
        if !output.status.success() {
            let last = stderr.lines().last().unwrap_or("no message");
            anyhow::bail!(
                "peer {}: {} failed: {last} ({})",
                self.name(),
                script.display(),
                self.needs()
            );
        }
        let ms = stdout
            .lines()
            .find_map(|l| l.strip_prefix("ms/step: "))
            .and_then(|v| v.trim().parse::<f64>().ok())
            .ok_or_else(|| {
                anyhow::anyhow!(
                    "peer {}: no `ms/step:` line in its output: {stdout}",
                    self.name()
                )
            })?;
        let line = stdout
            .lines()
            .find(|l| l.starts_with(self.name()))
            .unwrap_or(self.name())
            .to_string();
        let passes = stdout
            .lines()
            .filter(|l| l.starts_with("pass "))
            .map(str::to_string)
            .collect();
        Ok(PeerRun { line, ms, passes })
    }
}

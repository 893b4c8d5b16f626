//! Peers of `bench sim --peer`: other MPM codes stepped on the same case in the same run,
//! each through its script in `benches/peers/`.

use anyhow::Result;

use super::SimCase;

/// Another MPM code that `bench sim --peer` runs on the same case in the same run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Peer {
    /// Taichi on the CPU (`benches/peers/taichi_mpm.py`; `pip install taichi==1.7.4`).
    Taichi,
}

impl Peer {
    pub(super) fn name(self) -> &'static str {
        match self {
            Peer::Taichi => "taichi",
        }
    }

    /// The peer's script, next to the sources this program was built from.
    fn script(self) -> std::path::PathBuf {
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/peers/taichi_mpm.py")
    }

    /// Step `case` (a fixed-corotated cube) `steps` times in the peer: its description and
    /// its milliseconds per step.
    pub(super) fn run(self, case: &SimCase, steps: u32) -> Result<(String, f64)> {
        let script = self.script();
        if !script.is_file() {
            anyhow::bail!(
                "--peer {}: {} not found (it ships with the sources)",
                self.name(),
                script.display()
            );
        }
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
        let output = std::process::Command::new("python3")
            .arg(&script)
            .args(&args)
            .output()
            .map_err(|e| anyhow::anyhow!("--peer {}: cannot run python3: {e}", self.name()))?;
        let stdout = String::from_utf8_lossy(&output.stdout);
        let stderr = String::from_utf8_lossy(&output.stderr);
        if !output.status.success() {
            let last = stderr.lines().last().unwrap_or("no message");
            anyhow::bail!(
                "--peer {}: {} failed: {last} (pip install taichi==1.7.4)",
                self.name(),
                script.display()
            );
        }
        let ms = stdout
            .lines()
            .find_map(|l| l.strip_prefix("ms/step: "))
            .and_then(|v| v.trim().parse::<f64>().ok())
            .ok_or_else(|| {
                anyhow::anyhow!(
                    "--peer {}: no `ms/step:` line in its output: {stdout}",
                    self.name()
                )
            })?;
        let line = stdout
            .lines()
            .find(|l| l.starts_with(self.name()))
            .unwrap_or(self.name())
            .to_string();
        Ok((line, ms))
    }
}

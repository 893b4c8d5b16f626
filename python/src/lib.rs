//! `splatter._native`: the Python package's bridge to the library. Each function is a thin
//! call into `splatter` (its readers and writers, its scene parser, its run loop, its
//! renderer) with numpy arrays in and out; the package `splatter` (`pysrc/splatter/`)
//! gives them their Pythonic shape (classes, iterators, progress).

use std::path::PathBuf;

use glam::{Mat3, Quat, Vec3};
use numpy::ndarray::{Array1, Array2, Array3};
use numpy::{IntoPyArray, PyArray3, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3};
use pyo3::create_exception;
use pyo3::exceptions::{PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use splatter::gpu::{BackendChoice, GpuContext};
use splatter::render::{Camera, GpuRenderer, Splats};
use splatter::run::{Event, Input, Run, RunOptions};
use splatter::splat::formats::{read_splats_labelled, write_splats};
use splatter::splat::{GaussianCloud, NO_LABEL};

create_exception!(
    _native,
    SceneError,
    PyValueError,
    "A scene that does not parse or validate; the message names the field, its value and what was expected."
);

fn os_error(e: impl std::fmt::Display) -> PyErr {
    PyOSError::new_err(e.to_string())
}

fn run_error(e: anyhow::Error) -> PyErr {
    match e.downcast_ref::<splatter::scene::SceneError>() {
        Some(s) => SceneError::new_err(s.to_string()),
        None => PyRuntimeError::new_err(splatter::run::one_line(&e)),
    }
}

fn backend(name: Option<&str>) -> PyResult<Option<BackendChoice>> {
    Ok(match name {
        None => None,
        Some("vulkan") => Some(BackendChoice::Vulkan),
        Some("gl") => Some(BackendChoice::Gl),
        Some("metal") => Some(BackendChoice::Metal),
        Some("dx12") => Some(BackendChoice::Dx12),
        Some(other) => {
            return Err(PyValueError::new_err(format!(
                "backend {other:?}: expected \"vulkan\", \"gl\", \"metal\" or \"dx12\" (or None: the best adapter)"
            )))
        }
    })
}

fn open_gpu(name: Option<&str>) -> PyResult<GpuContext> {
    GpuContext::new(backend(name)?).map_err(|e| PyRuntimeError::new_err(e.to_string()))
}

/// The rows of an (n, k) array as vectors, checking the shape.
fn rows<const K: usize>(
    a: &PyReadonlyArray2<f32>,
    what: &str,
    n: usize,
) -> PyResult<Vec<[f32; K]>> {
    let a = a.as_array();
    if a.shape() != [n, K] {
        return Err(PyValueError::new_err(format!(
            "{what}: expected shape ({n}, {K}), got {:?}",
            a.shape()
        )));
    }
    Ok(a.rows()
        .into_iter()
        .map(|r| std::array::from_fn(|k| r[k]))
        .collect())
}

/// A cloud from arrays: means (n, 3), linear scales (n, 3), unit quaternions (n, 4) as
/// (w, x, y, z), opacities in (0, 1] (n,), SH (n, K, 3) coefficient-major.
#[allow(clippy::too_many_arguments)]
fn cloud_from_arrays(
    means: PyReadonlyArray2<f32>,
    scales: PyReadonlyArray2<f32>,
    rotations: PyReadonlyArray2<f32>,
    opacities: PyReadonlyArray1<f32>,
    sh: PyReadonlyArray3<f32>,
    labels: Option<PyReadonlyArray1<i32>>,
    label_names: Vec<String>,
) -> PyResult<GaussianCloud> {
    let n = means.as_array().shape()[0];
    let sh = sh.as_array();
    let coeffs = sh.shape()[1];
    let degree = match coeffs {
        1 => 0,
        4 => 1,
        9 => 2,
        16 => 3,
        k => {
            return Err(PyValueError::new_err(format!(
                "sh: expected shape ({n}, K, 3) with K = 1, 4, 9 or 16 (SH degree 0–3), got K = {k}"
            )))
        }
    };
    if sh.shape() != [n, coeffs, 3] {
        return Err(PyValueError::new_err(format!(
            "sh: expected shape ({n}, {coeffs}, 3), got {:?}",
            sh.shape()
        )));
    }
    let opacities = opacities.as_array();
    if opacities.len() != n {
        return Err(PyValueError::new_err(format!(
            "opacities: expected shape ({n},), got {:?}",
            opacities.shape()
        )));
    }
    let mut cloud = GaussianCloud {
        positions: rows::<3>(&means, "means", n)?
            .into_iter()
            .map(Vec3::from)
            .collect(),
        scales: rows::<3>(&scales, "scales", n)?
            .into_iter()
            .map(Vec3::from)
            .collect(),
        rotations: rows::<4>(&rotations, "rotations", n)?
            .into_iter()
            .map(|[w, x, y, z]| Quat::from_xyzw(x, y, z, w).normalize())
            .collect(),
        opacities: opacities.to_vec(),
        sh_degree: degree,
        sh: sh.iter().copied().collect(),
        ..Default::default()
    };
    if let Some(labels) = labels {
        let labels = labels.as_array();
        if labels.len() != n {
            return Err(PyValueError::new_err(format!(
                "labels: expected shape ({n},), got {:?}",
                labels.shape()
            )));
        }
        cloud.labels = labels
            .iter()
            .map(|l| match u16::try_from(*l) {
                Ok(v) if usize::from(v) < label_names.len() => Ok(v),
                _ if *l < 0 => Ok(NO_LABEL),
                _ => Err(PyValueError::new_err(format!(
                    "labels: {l} is not an index into the {} label names (−1: none)",
                    label_names.len()
                ))),
            })
            .collect::<PyResult<_>>()?;
        cloud.label_names = label_names;
    }
    cloud.check_consistent().map_err(PyValueError::new_err)?;
    Ok(cloud)
}

/// A cloud's arrays as a dict of numpy arrays (the keys of `splatter.Splats`).
fn cloud_to_dict<'py>(py: Python<'py>, cloud: &GaussianCloud) -> PyResult<Bound<'py, PyDict>> {
    let n = cloud.len();
    let flat3 = |v: &[Vec3]| -> Vec<f32> { v.iter().flat_map(|p| p.to_array()).collect() };
    let d = PyDict::new(py);
    let arr2 = |data: Vec<f32>, k: usize| Array2::from_shape_vec((n, k), data);
    let err = |e: numpy::ndarray::ShapeError| PyValueError::new_err(e.to_string());
    d.set_item(
        "means",
        arr2(flat3(&cloud.positions), 3)
            .map_err(err)?
            .into_pyarray(py),
    )?;
    d.set_item(
        "scales",
        arr2(flat3(&cloud.scales), 3).map_err(err)?.into_pyarray(py),
    )?;
    let wxyz: Vec<f32> = cloud
        .rotations
        .iter()
        .flat_map(|q| [q.w, q.x, q.y, q.z])
        .collect();
    d.set_item("rotations", arr2(wxyz, 4).map_err(err)?.into_pyarray(py))?;
    d.set_item(
        "opacities",
        Array1::from_vec(cloud.opacities.clone()).into_pyarray(py),
    )?;
    let k = splatter::splat::sh_coeff_count(cloud.sh_degree);
    d.set_item(
        "sh",
        Array3::from_shape_vec((n, k, 3), cloud.sh.clone())
            .map_err(err)?
            .into_pyarray(py),
    )?;
    if cloud.labels.is_empty() {
        d.set_item("labels", py.None())?;
    } else {
        let labels: Vec<i32> = cloud
            .labels
            .iter()
            .map(|l| if *l == NO_LABEL { -1 } else { i32::from(*l) })
            .collect();
        d.set_item("labels", Array1::from_vec(labels).into_pyarray(py))?;
    }
    d.set_item("label_names", cloud.label_names.clone())?;
    Ok(d)
}

/// Read a splat file of any format splatter reads (3DGS PLY, SuperSplat compressed PLY, SPZ,
/// SOG, .splat, GLB); a PLY's integer `label` (or `segment`) property gives the labels.
#[pyfunction]
fn read_splats<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let (cloud, _) = read_splats_labelled(&path, None).map_err(os_error)?;
    cloud_to_dict(py, &cloud)
}

/// Write arrays as a splat file, the format from the extension (.ply, .spz, .splat, .glb).
#[pyfunction]
#[pyo3(signature = (path, means, scales, rotations, opacities, sh, labels=None, label_names=Vec::new()))]
#[allow(clippy::too_many_arguments)]
fn write_splats_file(
    path: PathBuf,
    means: PyReadonlyArray2<f32>,
    scales: PyReadonlyArray2<f32>,
    rotations: PyReadonlyArray2<f32>,
    opacities: PyReadonlyArray1<f32>,
    sh: PyReadonlyArray3<f32>,
    labels: Option<PyReadonlyArray1<i32>>,
    label_names: Vec<String>,
) -> PyResult<()> {
    let cloud = cloud_from_arrays(means, scales, rotations, opacities, sh, labels, label_names)?;
    let format =
        splatter::splat::convert::output_format(&path, splatter::splat::spz::SpzVersion::V3)
            .map_err(PyValueError::new_err)?;
    write_splats(&path, &cloud, format).map_err(os_error)
}

/// Read, parse and validate a scene file: its JSON text (as written) and folder.
#[pyfunction]
fn load_scene(path: PathBuf) -> PyResult<(String, String)> {
    let scene = splatter::scene::load(&path).map_err(|e| SceneError::new_err(e.to_string()))?;
    let text = std::fs::read_to_string(&path).map_err(os_error)?;
    Ok((text, scene.base_dir.display().to_string()))
}

/// Parse and validate a scene's JSON text (`origin` names it in messages).
#[pyfunction]
fn check_scene(text: &str, origin: &str, base_dir: PathBuf) -> PyResult<String> {
    let scene = splatter::scene::parse(text, origin, &base_dir)
        .map_err(|e| SceneError::new_err(e.to_string()))?;
    Ok(scene.name)
}

/// Run a scene as `splatter render` does, into `out`: each frame's PNG, with `alpha` its
/// alpha pass (`out/alpha/`), and with `export_ply` / `export_particles` its Gaussians
/// (`out/gaussians/`) and particles (`out/particles/`). `on_frame(frame)` is called as each frame is rendered (its PNG is
/// then being written); returns the frames rendered.
#[pyfunction]
#[pyo3(signature = (path, text, origin, base_dir, out, frames, deterministic, backend_name, width, height, alpha, export_ply, export_particles, on_frame))]
#[allow(clippy::too_many_arguments)]
fn run_scene(
    py: Python<'_>,
    path: Option<PathBuf>,
    text: Option<String>,
    origin: String,
    base_dir: PathBuf,
    out: PathBuf,
    frames: Option<String>,
    deterministic: bool,
    backend_name: Option<String>,
    width: Option<u32>,
    height: Option<u32>,
    alpha: bool,
    export_ply: bool,
    export_particles: bool,
    on_frame: Py<PyAny>,
) -> PyResult<u32> {
    let input = match (path, text) {
        (Some(p), _) => Input::Scene(Some(p)),
        (None, Some(text)) => Input::Text {
            text,
            name: origin,
            base_dir,
        },
        (None, None) => Input::Scene(None),
    };
    let opts = RunOptions {
        input,
        out: Some(out.clone()),
        frames,
        width,
        height,
        deterministic,
        export_ply: export_ply.then(|| out.join("gaussians")),
        export_particles: export_particles.then(|| out.join("particles")),
        passes: if alpha {
            vec![splatter::output::passes::Pass::Alpha]
        } else {
            Vec::new()
        },
        ..RunOptions::default()
    };
    let run = Run::prepare(opts).map_err(run_error)?;
    let gpu = open_gpu(backend_name.as_deref())?;
    let mut failure: Option<PyErr> = None;
    let summary = py.detach(|| {
        run.execute(&gpu, &mut |event| {
            if let Event::FrameDone {
                frame,
                skipped: false,
            } = event
            {
                Python::attach(|py| {
                    if let Err(e) = on_frame.call1(py, (frame,)) {
                        failure.get_or_insert(e);
                    }
                });
            }
        })
    });
    if let Some(e) = failure {
        return Err(e);
    }
    Ok(summary.map_err(run_error)?.rendered)
}

/// A particle file's positions (m, 3), damage (m,) or None, and object index (m,) or None.
#[pyfunction]
fn read_particles<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let file = splatter::output::particles::read(&path).map_err(|e| os_error(format!("{e:#}")))?;
    let d = PyDict::new(py);
    let x: Vec<f64> = file.x.iter().flat_map(|p| p.to_array()).collect();
    let positions = Array2::from_shape_vec((file.x.len(), 3), x)
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    d.set_item("positions", positions.into_pyarray(py))?;
    match file.damage {
        Some(v) => d.set_item("damage", Array1::from_vec(v).into_pyarray(py))?,
        None => d.set_item("damage", py.None())?,
    }
    match file.object {
        Some(v) => d.set_item("object", Array1::from_vec(v).into_pyarray(py))?,
        None => d.set_item("object", py.None())?,
    }
    Ok(d)
}

/// A camera as (position, target, up, vertical field of view in degrees).
type LookAt = ([f32; 3], [f32; 3], [f32; 3], f32);

/// Render a cloud to an (height, width, 3) uint8 image. `camera` is (position, target, up,
/// vertical field of view in degrees); None frames the cloud as the quick look does (an
/// orbit round its robust bounds, about its estimated up).
#[pyfunction]
#[pyo3(signature = (means, scales, rotations, opacities, sh, width, height, camera=None, background=(0.0, 0.0, 0.0), backend_name=None))]
#[allow(clippy::too_many_arguments)]
fn render_splats<'py>(
    py: Python<'py>,
    means: PyReadonlyArray2<f32>,
    scales: PyReadonlyArray2<f32>,
    rotations: PyReadonlyArray2<f32>,
    opacities: PyReadonlyArray1<f32>,
    sh: PyReadonlyArray3<f32>,
    width: u32,
    height: u32,
    camera: Option<LookAt>,
    background: (f32, f32, f32),
    backend_name: Option<String>,
) -> PyResult<Bound<'py, PyArray3<u8>>> {
    if !(1..=splatter::scene::MAX_IMAGE_SIZE).contains(&width)
        || !(1..=splatter::scene::MAX_IMAGE_SIZE).contains(&height)
    {
        return Err(PyValueError::new_err(format!(
            "width {width}, height {height}: expected image sizes in 1..={}",
            splatter::scene::MAX_IMAGE_SIZE
        )));
    }
    let cloud = cloud_from_arrays(means, scales, rotations, opacities, sh, None, Vec::new())?;
    let camera = match camera {
        Some((position, target, up, fov)) => Camera::look_at(
            Vec3::from(position),
            Vec3::from(target),
            Vec3::from(up),
            fov.to_radians(),
            width,
            height,
        ),
        None => quick_look_camera(&cloud, width, height)?,
    };
    let splats = Splats::from_cloud(&cloud, Mat3::IDENTITY, Vec3::ZERO);
    let gpu = open_gpu(backend_name.as_deref())?;
    let bg = Vec3::from(background);
    let image = py.detach(|| {
        let mut renderer = GpuRenderer::new(&gpu);
        renderer.upload(&gpu, &splats)?;
        renderer.render(&gpu, &camera, bg)
    });
    let image = image.map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    let rgb: Vec<u8> = image
        .rgba
        .chunks_exact(4)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect();
    Ok(
        Array3::from_shape_vec((height as usize, width as usize, 3), rgb)
            .map_err(|e| PyValueError::new_err(e.to_string()))?
            .into_pyarray(py),
    )
}

/// The quick look's first camera for a cloud: an orbit round its robust bounds about its
/// estimated up direction, 50° field of view.
fn quick_look_camera(cloud: &GaussianCloud, width: u32, height: u32) -> PyResult<Camera> {
    if cloud.is_empty() {
        return Err(PyValueError::new_err(
            "camera=None frames the Gaussians, and there are none: pass a camera",
        ));
    }
    let up = splatter::splat::inspect::inspect(cloud).up;
    let bounds = splatter::splat::inspect::robust_bounds(&cloud.positions);
    let path = splatter::scene::CameraPath::orbit_framing(bounds, up, 50.0, width, height, 60);
    Ok(path.camera(0))
}

/// A PNG frame as an (height, width, 3) uint8 array, or (height, width, 4) with `rgba`.
#[pyfunction]
#[pyo3(signature = (path, rgba=false))]
fn read_frame<'py>(
    py: Python<'py>,
    path: PathBuf,
    rgba: bool,
) -> PyResult<Bound<'py, PyArray3<u8>>> {
    let image = image::open(&path).map_err(|e| os_error(format!("{}: {e}", path.display())))?;
    let (w, h) = (image.width() as usize, image.height() as usize);
    let (channels, bytes) = if rgba {
        (4, image.to_rgba8().into_raw())
    } else {
        (3, image.to_rgb8().into_raw())
    };
    Array3::from_shape_vec((h, w, channels), bytes)
        .map(|a| a.into_pyarray(py))
        .map_err(|e| PyValueError::new_err(e.to_string()))
}

/// The adapter a run would take (or the one `backend` forces), described.
#[pyfunction]
#[pyo3(signature = (backend_name=None))]
fn adapter(backend_name: Option<String>) -> PyResult<String> {
    Ok(open_gpu(backend_name.as_deref())?.describe())
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("SceneError", m.py().get_type::<SceneError>())?;
    m.add_function(wrap_pyfunction!(read_splats, m)?)?;
    m.add_function(wrap_pyfunction!(write_splats_file, m)?)?;
    m.add_function(wrap_pyfunction!(load_scene, m)?)?;
    m.add_function(wrap_pyfunction!(check_scene, m)?)?;
    m.add_function(wrap_pyfunction!(run_scene, m)?)?;
    m.add_function(wrap_pyfunction!(read_particles, m)?)?;
    m.add_function(wrap_pyfunction!(render_splats, m)?)?;
    m.add_function(wrap_pyfunction!(adapter, m)?)?;
    m.add_function(wrap_pyfunction!(read_frame, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}

//! Camera files of every format we read, against the INRIA `cameras.json` they were written
//! from by an independent script (`tests/data/captures/convert_cameras.py`, from the
//! formats' own definitions): a COLMAP model in text and in binary, a `transforms.json`, and
//! a nerfstudio `camera_path.json` in its normalised world with the run's
//! `dataparser_transforms.json`. Each gives the same cameras (to the files' rounding) and
//! the plant capture rendered through each, as a scene's camera path, matches its
//! `cameras.json` render; a run's exported cameras, read back, give its very frames.

use std::path::{Path, PathBuf};

use splatter::render::cpu;
use splatter::run::{Input, Run, RunOptions};
use splatter::scene::cameras::{self, CameraFormat, FileCamera};

fn data(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/captures")
        .join(path)
}

/// The plant's cameras in each format: name, path type, file, dataparser transforms.
const FORMATS: [(&str, &str, &str, Option<&str>); 4] = [
    (
        "COLMAP text",
        "colmap",
        "plant_formats/colmap/sparse/0",
        None,
    ),
    (
        "COLMAP binary",
        "colmap",
        "plant_formats/colmap_bin/sparse/0/images.bin",
        None,
    ),
    (
        "transforms.json",
        "transforms_json",
        "plant_formats/transforms.json",
        None,
    ),
    (
        "nerfstudio",
        "nerfstudio",
        "plant_formats/camera_path.json",
        Some("plant_formats/dataparser_transforms.json"),
    ),
];

fn truth() -> Vec<FileCamera> {
    cameras::read(&data("plant_cameras.json"), CameraFormat::Inria, None)
        .unwrap()
        .cameras
}

/// The largest differences between two camera lists: centres (m), rotation entries,
/// focal lengths (relative).
fn differences(a: &[FileCamera], b: &[FileCamera]) -> (f32, f32, f32) {
    assert_eq!(a.len(), b.len());
    let mut d = (0.0f32, 0.0f32, 0.0f32);
    for (x, y) in a.iter().zip(b) {
        assert_eq!((x.width, x.height), (y.width, y.height));
        d.0 = d.0.max(x.position.distance(y.position));
        let r = (x.rotation - y.rotation).to_cols_array();
        d.1 = d.1.max(r.iter().map(|v| v.abs()).fold(0.0, f32::max));
        d.2 =
            d.2.max((x.fx / y.fx - 1.0).abs().max((x.fy / y.fy - 1.0).abs()));
    }
    d
}

/// Each file is told by its content and gives the 24 training cameras, in order: centres
/// within 1e-5 m, rotations within 2e-5 (cameras.json holds six digits, its rotations
/// orthonormal only to about 1e-6), focal lengths within 1e-6.
#[test]
fn every_format_gives_the_training_cameras() {
    let truth = truth();
    for (name, _, file, dataparser) in FORMATS {
        let path = data(file);
        let format = CameraFormat::of(&path).unwrap();
        let want = match name {
            "COLMAP text" | "COLMAP binary" => CameraFormat::Colmap,
            "transforms.json" => CameraFormat::Transforms,
            _ => CameraFormat::Nerfstudio,
        };
        assert_eq!(format, want, "{name}");
        let read = cameras::read(&path, format, dataparser.map(data).as_deref()).unwrap();
        let (dp, dr, df) = differences(&read.cameras, &truth);
        eprintln!("{name}: centres within {dp:.1e} m, rotations {dr:.1e}, focal lengths {df:.1e}; warnings {:?}", read.warnings);
        assert!(
            dp < 1e-5 && dr < 2e-5 && df < 1e-6,
            "{name}: {dp} {dr} {df}"
        );
        assert!(read.warnings.is_empty(), "{name}: {:?}", read.warnings);
    }
    assert_eq!(
        CameraFormat::of(&data("plant_cameras.json")).unwrap(),
        CameraFormat::Inria
    );
}

/// The PNG bytes of frames 0–2 of the plant (untouched) seen by `camera`, at 192×108,
/// rendered deterministically into `dir/frames_NAME` (the frames' cameras also written to
/// `export_cameras`).
fn render_plant(
    dir: &Path,
    name: &str,
    camera: serde_json::Value,
    export_cameras: Option<PathBuf>,
) -> Vec<Vec<u8>> {
    let scene = serde_json::json!({
        "output": {"width": 192, "height": 108, "frames": 3},
        "camera": camera,
        "objects": [{"ply": data("plant_14k.spz")}],
    });
    let scene_file = dir.join(format!("{name}.json"));
    std::fs::write(&scene_file, scene.to_string()).unwrap();
    let out = dir.join(format!("frames_{name}"));
    let _ = std::fs::remove_dir_all(&out);
    let run = Run::prepare(RunOptions {
        input: Input::Scene(Some(scene_file)),
        out: Some(out.clone()),
        export_cameras,
        deterministic: true,
        ..RunOptions::default()
    })
    .unwrap();
    let gpu = splatter::gpu::GpuContext::new(None).expect("a wgpu adapter");
    run.execute(&gpu, &mut |_| {}).unwrap();
    (0..3)
        .map(|f| std::fs::read(out.join(format!("frame_{f:05}.png"))).unwrap())
        .collect()
}

/// RGBA bytes of a PNG.
fn rgba(png: &[u8]) -> Vec<u8> {
    image::load_from_memory(png).unwrap().to_rgba8().into_raw()
}

/// [`render_plant`] through a camera file's path (`path_type`), as RGBA.
fn render_through(
    dir: &Path,
    path_type: &str,
    file: &Path,
    dataparser: Option<PathBuf>,
) -> Vec<Vec<u8>> {
    let mut path = serde_json::json!({"type": path_type, "file": file});
    if let Some(d) = dataparser {
        path["dataparser_transforms"] = serde_json::json!(d);
    }
    let frames = render_plant(dir, path_type, serde_json::json!({"path": path}), None);
    frames.iter().map(|png| rgba(png)).collect()
}

/// The training views through each format's camera path against the same views through
/// the `cameras.json` path: PSNR ≥ 40 dB per frame (they differ by the files' rounding).
#[test]
fn training_views_render_alike_in_every_format() {
    let dir = tempfile::tempdir().unwrap();
    let reference = render_through(
        dir.path(),
        "cameras_json",
        &data("plant_cameras.json"),
        None,
    );
    for (name, path_type, file, dataparser) in FORMATS {
        let frames = render_through(dir.path(), path_type, &data(file), dataparser.map(data));
        for (f, (a, b)) in frames.iter().zip(&reference).enumerate() {
            let psnr = cpu::psnr(a, b);
            eprintln!("{name}: frame {f} {psnr:.1} dB against cameras.json");
            assert!(psnr >= 40.0, "{name} frame {f}: {psnr:.1} dB");
        }
    }
}

/// `--export-cameras`: an orbit's frames written as cameras.json and camera_path.json; the
/// scene rendered again through its own cameras.json gives the very bytes of its frames,
/// and through its camera_path.json within 40 dB (the field of view's round trip).
#[test]
fn exported_cameras_read_back_give_the_same_frames() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let orbit = serde_json::json!({"fov_y_deg": 45, "path": {"type": "orbit", "target": [0, 0, 0], "radius": 1.6, "height": 0.4, "turns": 0.3}});
    let orbit = render_plant(d, "orbit", orbit, Some(d.join("cams")));
    let inria =
        serde_json::json!({"path": {"type": "cameras_json", "file": d.join("cams/cameras.json")}});
    assert!(
        render_plant(d, "cameras_json", inria, None) == orbit,
        "the exported cameras.json does not give the orbit's frames"
    );
    let via_path = render_through(d, "nerfstudio", &d.join("cams/camera_path.json"), None);
    for (f, png) in orbit.iter().enumerate() {
        let psnr = cpu::psnr(&rgba(png), &via_path[f]);
        eprintln!("camera_path.json read back: frame {f} {psnr:.1} dB");
        assert!(psnr >= 40.0, "frame {f}: {psnr:.1} dB");
    }
}

/// The quick look (`render --ply --cameras FILE --camera I`) through the nerfstudio
/// `camera_path.json` with `--dataparser`: the same view as through the `cameras.json`
/// (PSNR ≥ 40 dB); without the dataparser the path stays in nerfstudio's normalised world
/// and the view is another (below 20 dB).
#[test]
fn the_quick_look_takes_a_camera_path_with_its_dataparser() {
    let dir = tempfile::tempdir().unwrap();
    let gpu = splatter::gpu::GpuContext::new(None).expect("a wgpu adapter");
    let look = |name: &str, cameras: &str, dataparser: Option<&str>| {
        let out = dir.path().join(name);
        let run = Run::prepare(RunOptions {
            input: Input::Ply {
                file: data("plant_14k.spz"),
                cameras: Some(data(cameras)),
                dataparser: dataparser.map(data),
                camera: Some(2),
                up: None,
            },
            out: Some(out.clone()),
            width: Some(192),
            height: Some(108),
            deterministic: true,
            ..RunOptions::default()
        })
        .unwrap();
        run.execute(&gpu, &mut |_| {}).unwrap();
        rgba(&std::fs::read(out.join("frame_00000.png")).unwrap())
    };
    let reference = look("inria", "plant_cameras.json", None);
    let path = "plant_formats/camera_path.json";
    let mapped = cpu::psnr(
        &look(
            "mapped",
            path,
            Some("plant_formats/dataparser_transforms.json"),
        ),
        &reference,
    );
    let unmapped = cpu::psnr(&look("unmapped", path, None), &reference);
    eprintln!("camera 2: {mapped:.1} dB with the dataparser, {unmapped:.1} dB without");
    assert!(mapped >= 40.0, "{mapped:.1} dB");
    assert!(unmapped < 20.0, "{unmapped:.1} dB");
}

/// Bad camera files are refused with their file, field and value.
#[test]
fn bad_camera_files_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let model = d.join("sparse");
    std::fs::create_dir_all(&model).unwrap();
    std::fs::write(
        model.join("cameras.txt"),
        "1 OPENCV_FISHEYE 100 80 50 50 50 40 0 0 0 0\n",
    )
    .unwrap();
    std::fs::write(model.join("images.txt"), "1 1 0 0 0 0 0 1 1 a.png\n\n").unwrap();
    let err = cameras::read_any(&model).unwrap_err().to_string();
    assert!(
        err.contains("cameras.txt") && err.contains("camera 1") && err.contains("OPENCV_FISHEYE"),
        "{err}"
    );
    std::fs::write(model.join("cameras.txt"), "1 PINHOLE 100 80 90 90 50 40\n").unwrap();
    std::fs::write(model.join("images.txt"), "1 1 0 0 0 0 0 1 7 a.png\n\n").unwrap();
    let err = cameras::read_any(&model).unwrap_err().to_string();
    assert!(err.contains("camera_id") && err.contains('7'), "{err}");
    std::fs::write(model.join("images.txt"), "1 2 0 0 0 0 0 1 1 a.png\n\n").unwrap();
    let err = cameras::read_any(&model).unwrap_err().to_string();
    assert!(err.contains("unit quaternion"), "{err}");

    let bin = d.join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    std::fs::write(bin.join("cameras.bin"), 5u64.to_le_bytes()).unwrap();
    std::fs::write(bin.join("images.bin"), 0u64.to_le_bytes()).unwrap();
    let err = cameras::read_any(&bin).unwrap_err().to_string();
    assert!(
        err.contains("cameras.bin") && err.contains("a count of 5"),
        "{err}"
    );

    let t = d.join("transforms.json");
    std::fs::write(
        &t,
        r#"{"w": 100, "h": 80, "frames": [{"transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}]}"#,
    )
    .unwrap();
    let err = cameras::read_any(&t).unwrap_err().to_string();
    assert!(err.contains("frames[0]") && err.contains("fl_x"), "{err}");

    let p = d.join("camera_path.json");
    std::fs::write(
        &p,
        r#"{"render_height": 80, "camera_path": [{"camera_to_world": [1, 0, 0], "fov": 50}]}"#,
    )
    .unwrap();
    let err = cameras::read_any(&p).unwrap_err().to_string();
    assert!(
        err.contains("camera_path[0].camera_to_world") && err.contains("3 numbers"),
        "{err}"
    );

    let other = d.join("other.json");
    std::fs::write(&other, r#"{"cameras": []}"#).unwrap();
    let err = cameras::read_any(&other).unwrap_err().to_string();
    assert!(err.contains("no camera file we know"), "{err}");
}

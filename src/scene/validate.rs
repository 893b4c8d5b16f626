//! Validation of a parsed scene: every number's range, and cross-field checks. Errors
//! name the file, the field path and the offending value.

use glam::Mat3;

use super::*;

pub(super) fn check_finite3(origin: &str, field: &str, v: [f32; 3]) -> Result<(), SceneError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(SceneError::invalid(
            origin,
            field,
            format!("{v:?}"),
            "finite numbers",
        ))
    }
}

pub(super) fn check_positive(origin: &str, field: &str, v: f32) -> Result<(), SceneError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(SceneError::invalid(origin, field, v, "a finite number > 0"))
    }
}

/// Error (message) when `r` is not a rotation matrix within `tol`.
pub(crate) fn rotation_problem(r: Mat3, tol: f32) -> Option<String> {
    let cols = r.to_cols_array();
    if !cols.iter().all(|x| x.is_finite()) {
        return Some("finite numbers".into());
    }
    let err = (r.transpose() * r - Mat3::IDENTITY)
        .to_cols_array()
        .iter()
        .fold(0.0f32, |m, x| m.max(x.abs()));
    if err > tol {
        return Some(format!(
            "an orthonormal matrix (|RᵀR − I| = {err:.2e} > {tol:.0e})"
        ));
    }
    if r.determinant() <= 0.0 {
        return Some("a rotation (determinant +1), not a reflection".into());
    }
    None
}

/// Camera-to-world matrix from an array of rows.
pub(crate) fn mat3_from_rows(rows: [[f32; 3]; 3]) -> Mat3 {
    Mat3::from_cols_array_2d(&rows).transpose()
}

impl Scene {
    /// Check every field's range; errors name the file, the field path and the value.
    /// (Runs after parsing; run it again after editing a scene by hand.)
    pub fn validate(&self) -> Result<(), SceneError> {
        self.validate_output()?;
        self.validate_camera()?;
        let o = self.origin.as_str();
        for (i, obj) in self.objects.iter().enumerate() {
            self.validate_object(i, obj)?;
            if let Some(sh) = &obj.shading {
                lighting::validate_shading(o, i, sh)?;
            }
        }
        if let Some(l) = &self.lighting {
            l.validate(o)?;
        }
        Ok(())
    }

    /// `output`: folder, image size, frame count, frame rate, background.
    fn validate_output(&self) -> Result<(), SceneError> {
        let o = self.origin.as_str();
        let out = &self.output;
        if let Some(dir) = &out.dir {
            if dir.as_os_str().is_empty() {
                return Err(SceneError::invalid(
                    o,
                    "output.dir",
                    "\"\"",
                    "a non-empty path",
                ));
            }
        }
        for (field, v) in [("output.width", out.width), ("output.height", out.height)] {
            if !(1..=MAX_IMAGE_SIZE).contains(&v) {
                return Err(SceneError::invalid(
                    o,
                    field,
                    v,
                    format!("a size in pixels in 1..={MAX_IMAGE_SIZE}"),
                ));
            }
        }
        if !(1..=MAX_FRAMES).contains(&out.frames) {
            return Err(SceneError::invalid(
                o,
                "output.frames",
                out.frames,
                format!("a frame count in 1..={MAX_FRAMES}"),
            ));
        }
        check_positive(o, "output.fps", out.fps)?;
        if !out
            .background
            .iter()
            .all(|c| c.is_finite() && (0.0..=1.0).contains(c))
        {
            return Err(SceneError::invalid(
                o,
                "output.background",
                format!("{:?}", out.background),
                "RGB components in [0, 1]",
            ));
        }
        Ok(())
    }

    /// `camera`: intrinsics (a field of view or both focal lengths), up vector and path.
    // Over 80 lines on purpose: one check per camera field in the scene format's order, each
    // with its own error.
    fn validate_camera(&self) -> Result<(), SceneError> {
        let o = self.origin.as_str();
        let cam = &self.camera;
        let is_cameras_json = cam.path.camera_file().is_some();
        match (cam.fov_y_deg, cam.fx, cam.fy) {
            (Some(fov), None, None) => {
                if !(fov.is_finite() && fov > 0.0 && fov < 180.0) {
                    return Err(SceneError::invalid(
                        o,
                        "camera.fov_y_deg",
                        fov,
                        "an angle in degrees in (0, 180)",
                    ));
                }
            }
            (None, Some(fx), Some(fy)) => {
                check_positive(o, "camera.fx", fx)?;
                check_positive(o, "camera.fy", fy)?;
            }
            (None, None, None) if is_cameras_json => {}
            (None, None, None) => {
                return Err(SceneError::invalid(
                    o,
                    "camera",
                    "no intrinsics",
                    "`fov_y_deg` (degrees) or `fx` and `fy` (pixels)",
                ))
            }
            (Some(fov), _, _) => {
                return Err(SceneError::invalid(
                    o,
                    "camera.fov_y_deg",
                    fov,
                    "either `fov_y_deg` or `fx` + `fy`, not both",
                ))
            }
            (None, Some(fx), None) => {
                return Err(SceneError::invalid(
                    o,
                    "camera.fy",
                    format!("missing (fx = {fx})"),
                    "`fx` and `fy` together",
                ))
            }
            (None, None, Some(fy)) => {
                return Err(SceneError::invalid(
                    o,
                    "camera.fx",
                    format!("missing (fy = {fy})"),
                    "`fx` and `fy` together",
                ))
            }
        }
        check_positive(o, "camera.near", cam.near)?;
        check_finite3(o, "camera.up", cam.up)?;
        if Vec3::from_array(cam.up).length() < 1e-6 {
            return Err(SceneError::invalid(
                o,
                "camera.up",
                format!("{:?}", cam.up),
                "a non-zero direction",
            ));
        }

        match &cam.path {
            PathSpec::Orbit(orbit) => {
                check_finite3(o, "camera.path.target", orbit.target)?;
                check_positive(o, "camera.path.radius", orbit.radius)?;
                for (field, v) in [
                    ("camera.path.height", orbit.height),
                    ("camera.path.start_deg", orbit.start_deg),
                    ("camera.path.turns", orbit.turns),
                ] {
                    if !v.is_finite() {
                        return Err(SceneError::invalid(o, field, v, "a finite number"));
                    }
                }
            }
            PathSpec::Keyframes(k) => self.validate_keyframes(&k.keyframes)?,
            PathSpec::CamerasJson(c)
            | PathSpec::Colmap(c)
            | PathSpec::TransformsJson(c)
            | PathSpec::Nerfstudio(c) => {
                let (_, format) = cam.path.camera_file().expect("a camera file");
                if c.file.as_os_str().is_empty() {
                    return Err(SceneError::invalid(
                        o,
                        "camera.path.file",
                        "\"\"",
                        format!("a path to a {}", format.name()),
                    ));
                }
                let full = self.base_dir.join(&c.file);
                let folder = format == super::cameras::CameraFormat::Colmap && full.is_dir();
                if !(full.is_file() || folder) {
                    return Err(SceneError::invalid(
                        o,
                        "camera.path.file",
                        format!("{:?}", c.file.display().to_string()),
                        format!("an existing file ({} not found)", full.display()),
                    ));
                }
            }
        }
        Ok(())
    }

    fn validate_keyframes(&self, keys: &[Keyframe]) -> Result<(), SceneError> {
        let o = self.origin.as_str();
        if keys.is_empty() {
            return Err(SceneError::invalid(
                o,
                "camera.path.keyframes",
                "[]",
                "at least one keyframe",
            ));
        }
        for (i, k) in keys.iter().enumerate() {
            let f = |name: &str| format!("camera.path.keyframes[{i}].{name}");
            if !k.time.is_finite() {
                return Err(SceneError::invalid(
                    o,
                    f("time"),
                    k.time,
                    "a finite time in seconds",
                ));
            }
            if i > 0 && k.time <= keys[i - 1].time {
                return Err(SceneError::invalid(
                    o,
                    f("time"),
                    k.time,
                    format!(
                        "a time after the previous keyframe's ({}): times must strictly increase",
                        keys[i - 1].time
                    ),
                ));
            }
            check_finite3(o, &f("position"), k.position)?;
            match (k.look_at, k.rotation) {
                (Some(t), None) => {
                    check_finite3(o, &f("look_at"), t)?;
                    if (Vec3::from_array(t) - Vec3::from_array(k.position)).length() < 1e-6 {
                        return Err(SceneError::invalid(
                            o,
                            f("look_at"),
                            format!("{t:?}"),
                            "a point away from `position`",
                        ));
                    }
                }
                (None, Some(rows)) => {
                    if let Some(problem) = rotation_problem(mat3_from_rows(rows), 1e-3) {
                        return Err(SceneError::invalid(
                            o,
                            f("rotation"),
                            format!("{rows:?}"),
                            problem,
                        ));
                    }
                }
                (Some(_), Some(_)) => {
                    return Err(SceneError::invalid(
                        o,
                        f("rotation"),
                        "given with `look_at`",
                        "either `look_at` or `rotation`, not both",
                    ))
                }
                (None, None) => {
                    return Err(SceneError::invalid(
                        o,
                        format!("camera.path.keyframes[{i}]"),
                        "no orientation",
                        "`look_at` [x, y, z] or `rotation` (3×3 rows)",
                    ))
                }
            }
        }
        Ok(())
    }

    fn validate_object(&self, i: usize, obj: &ObjectSpec) -> Result<(), SceneError> {
        let o = self.origin.as_str();
        let f = |name: &str| format!("objects[{i}].{name}");
        match (&obj.ply, &obj.procedural) {
            (Some(ply), None) => {
                if ply.as_os_str().is_empty() {
                    return Err(SceneError::invalid(
                        o,
                        f("ply"),
                        "\"\"",
                        "a path to a PLY file",
                    ));
                }
                let full = self.base_dir.join(ply);
                if !full.is_file() {
                    return Err(SceneError::invalid(
                        o,
                        f("ply"),
                        format!("{:?}", ply.display().to_string()),
                        format!("an existing file ({} not found)", full.display()),
                    ));
                }
            }
            (None, Some(spec)) => spec.validate().map_err(|e| match e {
                ProceduralError::Invalid {
                    field,
                    value,
                    expected,
                } => SceneError::invalid(o, f(&format!("procedural.{field}")), value, expected),
                other => SceneError::invalid(o, f("procedural"), "", one_line(&other.to_string())),
            })?,
            (Some(_), Some(_)) => {
                return Err(SceneError::invalid(
                    o,
                    f("procedural"),
                    "given with `ply`",
                    "exactly one source: `ply` or `procedural`",
                ))
            }
            (None, None) => {
                return Err(SceneError::invalid(
                    o,
                    format!("objects[{i}]"),
                    "no source",
                    "`ply` (a file) or `procedural` (a shape)",
                ))
            }
        }
        let t = &obj.transform;
        check_finite3(o, &f("transform.translate"), t.translate)?;
        check_finite3(o, &f("transform.rotate_deg"), t.rotate_deg)?;
        if let Some(cameras) = t.up.as_ref().and_then(UpSpec::auto_cameras) {
            self.check_up_cameras(i, obj, cameras)?;
        }
        if let Some(up) = &t.up {
            if !up.is_auto() && up.vector().is_none() {
                let value = serde_json::to_string(up).unwrap_or_default();
                return Err(SceneError::invalid(
                    o,
                    f("transform.up"),
                    value,
                    "\"auto\", a signed axis (\"+x\", \"-x\", \"+y\", \"-y\", \"+z\", \"-z\") or a non-zero vector [x, y, z]",
                ));
            }
        }
        let s = t.scale.as_vec3();
        if !s.is_finite() || s.min_element() <= 0.0 {
            let value = match t.scale {
                Scale::Uniform(v) => v.to_string(),
                Scale::PerAxis(v) => format!("{v:?}"),
            };
            return Err(SceneError::invalid(
                o,
                f("transform.scale"),
                value,
                "finite scale factors > 0",
            ));
        }
        Ok(())
    }

    /// `transform.up.auto.cameras`: an existing file, for a capture (a procedural object is
    /// z-up already).
    fn check_up_cameras(
        &self,
        i: usize,
        obj: &ObjectSpec,
        cameras: &Path,
    ) -> Result<(), SceneError> {
        let field = format!("objects[{i}].transform.up.auto.cameras");
        let value = format!("{:?}", cameras.display().to_string());
        if obj.ply.is_none() {
            return Err(SceneError::invalid(
                &self.origin,
                field,
                value,
                "cameras only for a capture (`ply`): a procedural object is z-up",
            ));
        }
        let full = self.base_dir.join(cameras);
        if cameras.as_os_str().is_empty() || !full.is_file() {
            return Err(SceneError::invalid(
                &self.origin,
                field,
                value,
                format!("an existing cameras.json ({} not found)", full.display()),
            ));
        }
        Ok(())
    }
}

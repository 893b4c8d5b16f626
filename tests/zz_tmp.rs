#[test]
fn show() {
    let t = "{\n  \"output\": {\"width\": 64, \"height\": 48, \"frames\": 1},\n  \"camera\": {\n    \"fovy\": 40,\n    \"path\": {\"type\": \"orbit\", \"radius\": 2}\n  }\n}\n";
    eprintln!("{}", splatter::scene::parse(t, "scenes/x.json", std::path::Path::new(".")).unwrap_err());
    let t = r#"{"output": {"width": 64, "height": 48, "frames": 1}, "camera": {"fov_y_deg": 40, "path": {"type": "orbit", "radius": 2}}, "objects": [{"procedural": {"shape": "sphere", "radius": 1, "spacing": 0.1, "color": [1,1,1]}, "transform": {"scale": [1, 2]}}]}"#;
    eprintln!("{}", splatter::scene::parse(t, "scenes/x.json", std::path::Path::new(".")).unwrap_err());
}

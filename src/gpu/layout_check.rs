//! Test support: check that a `#[repr(C)]` Rust struct and the WGSL struct it mirrors have
//! the same size and member offsets, using naga's layouter on the shader source.

use wgpu::naga;

/// `source` parsed and validated by naga (every check, no optional capability); a failure
/// panics with naga's report on the source.
pub fn validated_module(source: &str) -> naga::Module {
    let module = naga::front::wgsl::parse_str(source)
        .unwrap_or_else(|e| panic!("{}", e.emit_to_string(source)));
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::empty(),
    )
    .validate(&module)
    .unwrap_or_else(|e| panic!("{}", e.emit_to_string(source)));
    module
}

/// Size and (name, offset) of every member of the WGSL struct `name` in `source`.
pub fn naga_struct(source: &str, name: &str) -> (u32, Vec<(String, u32)>) {
    let module = naga::front::wgsl::parse_str(source).expect("WGSL parses");
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).expect("layout");
    for (_, ty) in module.types.iter() {
        if ty.name.as_deref() == Some(name) {
            if let naga::TypeInner::Struct { members, span } = &ty.inner {
                let members = members
                    .iter()
                    .map(|m| (m.name.clone().unwrap_or_default(), m.offset))
                    .collect();
                return (*span, members);
            }
        }
    }
    panic!("struct {name} not found in WGSL");
}

/// `assert_layout!(wgsl_source, RustType, "WgslName", [field, …])`: equal sizes, and each
/// listed field at the offset of the WGSL member of the same name.
macro_rules! assert_layout {
    ($src:expr, $ty:ty, $name:literal, [$($field:ident),* $(,)?]) => {{
        let (span, members) = $crate::gpu::layout_check::naga_struct($src, $name);
        assert_eq!(span as usize, std::mem::size_of::<$ty>(), "size of {}", $name);
        $(
            let (_, woff) = members
                .iter()
                .find(|(w, _)| w == stringify!($field))
                .unwrap_or_else(|| panic!("{} has no member {}", $name, stringify!($field)));
            assert_eq!(*woff as usize, std::mem::offset_of!($ty, $field), "{}.{}", $name, stringify!($field));
        )*
    }};
}
pub(crate) use assert_layout;

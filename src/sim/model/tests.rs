use super::*;
use wgpu::naga;

/// The value of the WGSL constant `name` in `module`, as naga reads it.
fn wgsl_u32_constant(module: &naga::Module, name: &str) -> Option<u32> {
    let (_, c) = module
        .constants
        .iter()
        .find(|(_, c)| c.name.as_deref() == Some(name))?;
    match module.global_expressions[c.init] {
        naga::Expression::Literal(naga::Literal::U32(v)) => Some(v),
        ref other => panic!("{name} = {other:?}: expected a u32 literal"),
    }
}

/// A simulation's passes dispatch on its own models only and hold only their WGSL, and
/// the library still validates with the others left out.
#[test]
fn a_simulation_dispatches_only_its_models() {
    let used = ModelsUsed::of(&[
        super::super::Material::fixed_corotated(1e4, 0.3),
        super::super::Material::fixed_corotated(2e4, 0.2),
    ]);
    assert_eq!(used.elastic, [ElasticModel::FixedCorotated]);
    assert_eq!(used.plastic, [PlasticModel::None]);
    let src = format!(
        "{}\n{}",
        super::super::gpu::wgsl::library(),
        wgsl_for(&used)
    );
    crate::gpu::layout_check::validated_module(&src);
    assert!(src.contains("case ELASTIC_FIXED_COROTATED"));
    assert!(!src.contains("case ELASTIC_NEO_HOOKEAN"));
    assert!(!src.contains("case PLASTIC_NACC"));
    // Nor are the other laws' functions compiled in; a NACC material brings its own.
    assert!(!src.contains("fn nacc_return_map("));
    assert!(!src.contains("fn brittle_"));
    let (law, _) = PlasticModel::Nacc.example(2000.0, 0.3).unwrap();
    let nacc = ModelsUsed::of(&[super::super::Material::with_plastic(law, 2000.0, 0.3)]);
    assert!(wgsl_for(&nacc).contains("fn nacc_return_map("));
    let all = wgsl();
    for m in ElasticModel::ALL {
        assert!(all.contains(&format!("case ELASTIC_{}", m.def().name.to_uppercase())));
    }
}

/// The code each model carries to the GPU (written into `SimMaterial` by the Rust
/// side) is the value of its `ELASTIC_*`/`PLASTIC_*` constant in the generated WGSL, as
/// an independent parser (naga) reads it after the whole library validates; the codes
/// and names are distinct, so no two models share a dispatch case.
#[test]
fn wgsl_constants_are_the_codes_the_gpu_record_carries() {
    let src = format!("{}\n{}", super::super::gpu::wgsl::library(), wgsl());
    let module = crate::gpu::layout_check::validated_module(&src);
    let mut seen = std::collections::HashSet::new();
    let elastic = ElasticModel::ALL
        .iter()
        .map(|m| ("ELASTIC", m.def().name, m.code()));
    let plastic = PlasticModel::ALL
        .iter()
        .map(|m| ("PLASTIC", m.name(), m.code()));
    for (kind, name, code) in elastic.chain(plastic) {
        let constant = format!("{kind}_{}", name.to_uppercase());
        assert_eq!(
            wgsl_u32_constant(&module, &constant),
            Some(code),
            "{constant} against the code Rust writes"
        );
        assert!(
            seen.insert((kind, code)),
            "{constant}: code {code} taken twice"
        );
    }
    for names in [
        ElasticModel::ALL
            .iter()
            .map(|m| m.def().name)
            .collect::<Vec<_>>(),
        PlasticModel::ALL.iter().map(|m| m.name()).collect(),
    ] {
        let unique: std::collections::HashSet<_> = names.iter().collect();
        assert_eq!(unique.len(), names.len(), "model names {names:?}");
    }
}

#[test]
fn generated_wgsl_names_every_model() {
    let src = wgsl();
    assert!(
        src.contains("const ELASTIC_FIXED_COROTATED: u32 = 0u;"),
        "{src}"
    );
    assert!(
        src.contains("const ELASTIC_NEO_HOOKEAN: u32 = 1u;"),
        "{src}"
    );
    assert!(src.contains("const PLASTIC_NACC: u32 = 1u;"), "{src}");
    assert!(src.contains("case ELASTIC_NEO_HOOKEAN: { return elastic_kirchhoff_neo_hookean("));
}

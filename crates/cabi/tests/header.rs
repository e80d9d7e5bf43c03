//! The header a model library is built with (templates/cabi/toolconf_model.h.tera, rendered here
//! for the renderer's fixture model) declares this crate's ABI: compiled by the C compiler (`cc`,
//! or `CC`) with every struct's size and every field's offset asserted equal to the Rust
//! `#[repr(C)]` types', every function assigned to a pointer of the C type its export has (a
//! mismatch is an error under -Werror), and every status code and symbol name as this crate has
//! them.

use std::path::Path;
use std::process::Command;

use toolconf_cabi::exports::SYMBOLS;
use toolconf_cabi::{status, Constraint, Domain, InertiaRule, ModelInfo};
use toolconf_render::cabi::{render_library, LibraryPackage};

/// The rendered header of the fixture model.
fn header() -> String {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let ir = toolconf_render::read_ir(&root.join("tests/fixtures/pendulum.json")).expect("fixture");
    let package = LibraryPackage::for_model("pendulum", Path::new("/repository"));
    let files = render_library(&ir, &root.join("templates/cabi"), &package).expect("render");
    files
        .into_iter()
        .find(|f| f.path == Path::new("toolconf_model.h"))
        .expect("toolconf_model.h")
        .contents
}

/// `offsetof` assertions of each named field, and the struct's size.
macro_rules! layout {
    ($c:literal, $t:ty, [$($f:ident),* $(,)?]) => {{
        let mut out = format!(
            "_Static_assert(sizeof({}) == {}, \"sizeof {}\");\n",
            $c, std::mem::size_of::<$t>(), $c
        );
        $(
            out += &format!(
                "_Static_assert(offsetof({}, {}) == {}, \"{}.{}\");\n",
                $c, stringify!($f), std::mem::offset_of!($t, $f), $c, stringify!($f)
            );
        )*
        out
    }};
}

/// The C type of each export, as the Rust signature in `Exports` says (by hand: the compiler
/// then checks the header against it).
const SIGNATURES: [(&str, &str); 23] = [
    ("toolconf_abi_version", "uint32_t (*)(void)"),
    ("toolconf_tasks_fingerprint", "const char *(*)(void)"),
    ("toolconf_model_info", "const toolconf_metadata *(*)(void)"),
    ("toolconf_last_error", "const char *(*)(void)"),
    ("toolconf_status_name", "const char *(*)(int32_t)"),
    ("toolconf_check_tool", "int32_t (*)(const double *)"),
    ("toolconf_dynamics", "int32_t (*)(const double *, const double *, const double *, double *)"),
    ("toolconf_dynamics_jacobian", "int32_t (*)(const double *, const double *, const double *, double *, double *)"),
    ("toolconf_rigid_body_dynamics", "int32_t (*)(const double *, const double *, const double *, double *)"),
    ("toolconf_tip", "int32_t (*)(const double *, const double *, double *, double *)"),
    ("toolconf_tip_bias", "int32_t (*)(const double *, const double *, const double *, double *)"),
    ("toolconf_state_matrix", "int32_t (*)(const double *, double *)"),
    ("toolconf_input_matrix", "int32_t (*)(const double *, double *)"),
    ("toolconf_task_defaults", "int32_t (*)(uint32_t, double *, double *)"),
    ("toolconf_sensitivities", "int32_t (*)(uint32_t, const double *, double *, int32_t *)"),
    ("toolconf_pi_u", "int32_t (*)(uint32_t, const double *, const double *, double *)"),
    ("toolconf_logdet_gradient", "int32_t (*)(uint32_t, const double *, const double *, double *)"),
    ("toolconf_control_confidence", "int32_t (*)(uint32_t, const double *, const double *, const double *, double *, double *)"),
    ("toolconf_controller_create", "int32_t (*)(const double *, uint32_t, const double *, const double *, double, const double *, double, toolconf_controller **)"),
    ("toolconf_controller_destroy", "int32_t (*)(toolconf_controller *)"),
    ("toolconf_controller_tick", "int32_t (*)(toolconf_controller *, const double *, double *, double *)"),
    ("toolconf_controller_tick_with_acceleration", "int32_t (*)(toolconf_controller *, const double *, const double *, double *, double *)"),
    ("toolconf_controller_pi_u", "int32_t (*)(const toolconf_controller *, double *)"),
];

#[test]
fn the_header_declares_this_crates_abi() {
    let h = header();
    // Every symbol, in Exports' order, with a signature above; nothing else exported.
    assert_eq!(SIGNATURES.map(|(s, _)| s), SYMBOLS);
    for symbol in SYMBOLS {
        assert!(
            h.contains(&format!("{symbol}(")),
            "{symbol} is not declared"
        );
    }
    for (code, name) in status::NAMES.iter().enumerate() {
        let name = name.to_str().unwrap();
        assert!(h.contains(&format!("#define {name} {code}\n")), "{name}");
    }
    assert!(h.contains(&format!(
        "#define TOOLCONF_ABI_VERSION {}u\n",
        toolconf_cabi::ABI_VERSION
    )));

    compiles(&h, &layouts_and_signatures());
}

/// A C file that asserts (with `_Static_assert`) each struct's layout and assigns each export
/// to a pointer of its signature.
fn layouts_and_signatures() -> String {
    let mut c = String::from("#include <stddef.h>\n#include \"toolconf_model.h\"\n");
    c += &layout!("toolconf_domain", Domain, [lo, hi, lo_open, hi_open, rule]);
    c += &layout!("toolconf_constraint", Constraint, [coefficients, rule]);
    c += &layout!(
        "toolconf_inertia_rule",
        InertiaRule,
        [moments, products, slack, rule]
    );
    c += &layout!(
        "toolconf_metadata",
        ModelInfo,
        [
            abi_version,
            name,
            title,
            description,
            dof,
            state_dim,
            parameter_count,
            tip_dim,
            has_tip,
            parameter_names,
            parameter_units,
            state_names,
            control_names,
            domains,
            constraint_count,
            constraints,
            sample_lo,
            sample_hi,
            has_default,
            defaults,
            has_inertia,
            inertia,
            equilibrium_state,
            equilibrium_control,
            task_count,
            task_names,
            task_offered,
            term_count,
            term_names,
            tasks_fingerprint,
        ]
    );
    for (symbol, signature) in SIGNATURES {
        let pointer = signature.replacen("(*)", &format!("(*p_{symbol})"), 1);
        c += &format!("{pointer} = {symbol};\n");
    }
    c
}

/// The header `h` compiles with `c` (the layouts) as C11, and alone as C++11.
fn compiles(h: &str, c: &str) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("toolconf_model.h"), h).unwrap();
    std::fs::write(dir.path().join("layout.c"), c).unwrap();
    std::fs::write(dir.path().join("include.cpp"), "#include \"toolconf_model.h\"\nint main() { return toolconf_abi_version() == TOOLCONF_ABI_VERSION ? 0 : 1; }\n").unwrap();
    // As C11 with the layouts and signatures; as C++ (the extern "C" block), included alone.
    for (file, standard) in [("layout.c", "-std=c11"), ("include.cpp", "-std=c++11")] {
        let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
        let language = if file.ends_with(".c") { "c" } else { "c++" };
        let out = Command::new(&cc)
            .args([
                "-x",
                language,
                standard,
                "-Wall",
                "-Wextra",
                "-Werror",
                "-pedantic",
                "-c",
            ])
            .arg(dir.path().join(file))
            .arg("-o")
            .arg(dir.path().join(format!("{file}.o")))
            .current_dir(dir.path())
            .output()
            .unwrap_or_else(|e| {
                panic!("cannot run the C compiler {cc} (make test needs one): {e}")
            });
        assert!(
            out.status.success(),
            "{cc} {standard} rejected the header or a layout:\n{}\n{c}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

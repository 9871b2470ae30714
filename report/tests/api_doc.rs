//! docs/API.md's parameter table is the rendering of `solver::case::PARAMETERS`.
//! `UPDATE_DOCS=1 cargo test -p knotsweep-report --test api_doc` rewrites it.
use report::parameters::{parameters_section, with_section};
use std::path::PathBuf;

#[test]
fn api_md_parameter_table_is_current() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../docs/API.md");
    let document = std::fs::read_to_string(&path).expect("docs/API.md");
    let current =
        with_section(&document, &parameters_section()).expect("docs/API.md has the parameter section");
    if std::env::var_os("UPDATE_DOCS").is_some() {
        std::fs::write(&path, current).expect("writing docs/API.md");
        return;
    }
    assert!(
        current == document,
        "docs/API.md's parameter table differs from solver::case::PARAMETERS; regenerate it with \
         `UPDATE_DOCS=1 cargo test -p knotsweep-report --test api_doc`"
    );
}

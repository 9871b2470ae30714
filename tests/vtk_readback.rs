//! The ParaView files read back by VTK's own XML readers (the `vtk` package
//! from PyPI, the readers ParaView uses): those of `knotsweep run --vtk` and
//! those of `GET /api/cases/{id}/snapshots.zip`. Each centre line has one point
//! per node and its fields, each contact file its forces, and the `.pvd`'s
//! times increase. The `.pvd` checks need only `python3`, the readers its
//! `vtk` module: without them the checks are skipped with the reason, or fail
//! when `CI` is set (`common::missing`).
mod common;

use common::*;
use reqwest::StatusCode;
use std::path::Path;
use std::process::Command;

/// Checks the `.pvd` at `argv[1]` and its files, a centre line per rod of
/// `argv[2]` nodes (comma separated: a bend's rods are parts 0 and 1, the
/// contacts the last part); `argv[3]`, when given, is a zip to unpack beside
/// the `.pvd` first.
/// Exit 3: no `vtk` module (the XML checks passed).
const CHECK: &str = r#"
import os, sys, zipfile, xml.etree.ElementTree as ET
pvd, nodes = sys.argv[1], [int(n) for n in sys.argv[2].split(",")]
if len(sys.argv) > 3:
    zipfile.ZipFile(sys.argv[3]).extractall(os.path.dirname(pvd))
sets = ET.parse(pvd).getroot().findall("./Collection/DataSet")
parts = {}
for s in sets:
    parts.setdefault(int(s.get("part")), []).append((float(s.get("timestep")), s.get("file")))
assert sorted(parts) == list(range(len(nodes) + 1)), parts.keys()
for part in parts.values():
    times = [t for t, _ in part]
    assert len(times) >= 2 and all(a < b for a, b in zip(times, times[1:])), f"times not increasing: {times}"
try:
    import vtk
except ImportError as e:
    print(f"no vtk module ({e}): pip install vtk"); sys.exit(3)
def read(f):
    r = vtk.vtkXMLPolyDataReader(); r.SetFileName(os.path.join(os.path.dirname(pvd), f)); r.Update()
    assert r.GetErrorCode() == 0, f
    out = r.GetOutput(); pd = out.GetPointData()
    arrays = {pd.GetArrayName(i): pd.GetArray(i).GetNumberOfComponents() for i in range(pd.GetNumberOfArrays())}
    return out, arrays, out.GetFieldData().GetArray("TimeValue").GetValue(0)
contacts = 0
for k, (t, g) in enumerate(parts[len(nodes)]):
    for rod, n in enumerate(nodes):
        f = parts[rod][k][1]
        line, arrays, time = read(f)
        assert line.GetNumberOfPoints() == n and line.GetNumberOfLines() == 1, (f, line.GetNumberOfPoints())
        assert arrays == {"radius": 1, "twist_rate": 1, "curvature": 1, "velocity": 3}, (f, arrays)
        assert time == t, (f, time, t)
    points, arrays, _ = read(g)
    assert points.GetNumberOfVerts() == points.GetNumberOfPoints(), g
    assert arrays == {"stick": 1, "normal_force": 3, "friction_force": 3}, (g, arrays)
    contacts += points.GetNumberOfPoints()
assert contacts > 0, "no contact in any snapshot"
print(f"vtk {vtk.vtkVersion.GetVTKVersion()} read {len(sets)} files: {nodes} points per centre line, {contacts} contacts")
"#;

/// Runs [`CHECK`] (panicking on a failed check; [`missing`] without python3 or VTK).
fn check(pvd: &Path, nodes: &[usize], zip: Option<&Path>) {
    let nodes: Vec<String> = nodes.iter().map(usize::to_string).collect();
    let mut cmd = Command::new("python3");
    cmd.args(["-c", CHECK]).arg(pvd).arg(nodes.join(",")).args(zip);
    let out = match cmd.output() {
        Ok(out) => out,
        Err(e) => return missing(&format!("no python3 ({e})")),
    };
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    match out.status.code() {
        Some(0) => println!("{text}"),
        Some(3) => missing(&format!("the VTK readers: {text}")),
        _ => panic!("the VTK files do not read back: {text}"),
    }
}

#[test]
fn run_vtk_files_read_back() {
    let dir = tempfile::tempdir().unwrap();
    let status = Command::new(env!("CARGO_BIN_EXE_knotsweep"))
        .args([
            "run",
            "--n",
            "1",
            "--length",
            "0.3",
            "--nodes",
            "102",
            "--relax-time",
            "0.1",
        ])
        .args(["--pull-speed", "0.01", "--min-l-k-bar", "100", "--out"])
        .arg(dir.path().join("tiny.json"))
        .arg("--vtk")
        .arg(dir.path().join("vtk"))
        .status()
        .expect("knotsweep runs");
    assert!(status.success());
    check(&dir.path().join("vtk/tiny.pvd"), &[102], None);
}

/// A bend: a block per rod, each of its own nodes, then the contacts.
#[test]
fn a_bends_rods_read_back_as_a_block_each() {
    let dir = tempfile::tempdir().unwrap();
    let status = Command::new(env!("CARGO_BIN_EXE_knotsweep"))
        .args(["run", "--knot", "reef", "--length", "0.4", "--nodes", "121"])
        .args([
            "--relax-time",
            "0.1",
            "--pull-speed",
            "0.01",
            "--min-l-k-bar",
            "100",
            "--out",
        ])
        .arg(dir.path().join("reef.json"))
        .arg("--vtk")
        .arg(dir.path().join("vtk"))
        .status()
        .expect("knotsweep runs");
    assert!(status.success());
    check(&dir.path().join("vtk/reef.pvd"), &[121, 121], None);
}

#[tokio::test]
async fn snapshots_zip_reads_back() {
    let (dir, db) = temp_db();
    let server = start(config(&db, 1)).await;
    let (url, c) = (server.url(), client());
    let (status, _) = get_text(&c, &format!("{url}/api/cases/999/snapshots.zip")).await;
    assert_eq!(status, StatusCode::NOT_FOUND);
    let base = with(tiny_base(), serde_json::json!({"min_l_k_bar": 115.0}));
    let id = submit_sweep(&c, &url, &serde_json::json!({ "base": base })).await;
    let sweep = wait_sweep(&c, &url, id, std::time::Duration::from_secs(300), finished).await;
    let case = case_ids(&sweep)[0];
    let r = c
        .get(format!("{url}/api/cases/{case}/snapshots.zip"))
        .send()
        .await
        .unwrap();
    assert_eq!(r.status(), StatusCode::OK);
    assert_eq!(r.headers()["content-type"], "application/zip");
    assert_eq!(
        r.headers()["content-disposition"],
        format!("attachment; filename=\"case-{case}-snapshots.zip\"").as_str()
    );
    let zip = dir.path().join("snapshots.zip");
    std::fs::write(&zip, r.bytes().await.unwrap()).unwrap();
    check(&dir.path().join(format!("case-{case}.pvd")), &[121], Some(&zip));
    server.shutdown().await.unwrap();
}

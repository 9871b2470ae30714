//! A case's snapshots for ParaView: per snapshot VTK XML PolyData files,
//! a centre line per rod and the loaded contacts, and a `.pvd` collection
//! that orders them in time, each snapshot's files its parts (ParaView opens
//! the `.pvd` as one multiblock data set per time, a block per part).
//!
//! Centre line of a one-rod knot (`centreline_NNN.vtp`, part 0), or of each
//! rod of a bend (`rod_R_NNN.vtp`, part R, block `rod_R`): the rod's nodes
//! (m) joined by one polyline, with point data `radius` (h, m), `twist_rate`
//! and `curvature` (1/m) and `velocity` (m/s). Contacts (`contacts_NNN.vtp`,
//! the last part): a vertex midway between the two closest points of each
//! loaded contact, with `normal_force` and `friction_force` (N, on the first
//! segment's rod) and `stick` (1: inside the friction cone, 0: slipping).
//! Each carries field data `TimeValue` (s) and `l_k_bar`.
mod xml;

use solver::protocol::Snapshot;
use std::ops::Range;
use xml::{Array, Cells, DataSet, Values};

/// A file to write: its path relative to the output directory (`/`
/// separated) and its text.
pub struct VtkFile {
    pub path: String,
    pub text: String,
}

/// The files of `snapshots` of a case of rod radius `radius` (m), named after
/// `name`: `{name}.pvd` and, in time order, `{name}/centreline_NNN.vtp` (or
/// per rod of a bend `{name}/rod_R_NNN.vtp`) and `{name}/contacts_NNN.vtp`.
pub fn case_files(name: &str, radius: f64, snapshots: &[Snapshot]) -> Vec<VtkFile> {
    let ordered = in_time(snapshots);
    let rods = ordered
        .iter()
        .map(|(_, f)| f.rods.len())
        .max()
        .unwrap_or(0)
        .max(1);
    let parts: Vec<String> = match rods {
        1 => vec!["centreline".to_string()],
        _ => (0..rods).map(|r| format!("rod_{r}")).collect(),
    }
    .into_iter()
    .chain(["contacts".to_string()])
    .collect();
    let mut files = Vec::with_capacity(1 + parts.len() * ordered.len());
    for (k, (time, f)) in ordered.iter().enumerate() {
        let lines = node_ranges(f)
            .into_iter()
            .map(|nodes| centreline(f, nodes, radius, *time));
        for (part, text) in lines.chain([contacts(f, *time)]).enumerate() {
            let path = format!("{name}/{}_{k:03}.vtp", parts[part]);
            files.push(VtkFile { path, text });
        }
    }
    let comments: Vec<String> = ordered
        .iter()
        .map(|(t, f)| format!("{}: l_k bar {:.2}, t = {t:.4} s", f.label, f.l_k_bar))
        .collect();
    let sets: Vec<DataSet> = files
        .iter()
        .enumerate()
        .map(|(i, file)| {
            let (k, part) = (i / parts.len(), i % parts.len());
            DataSet {
                timestep: ordered[k].0,
                part,
                name: &parts[part],
                file: &file.path,
                comment: if part == 0 { &comments[k] } else { "" },
            }
        })
        .collect();
    let pvd = VtkFile {
        path: format!("{name}.pvd"),
        text: xml::collection(&sets),
    };
    std::iter::once(pvd).chain(files).collect()
}

/// The nodes of each rod of `f` in its `points`: all of them for one rod.
fn node_ranges(f: &Snapshot) -> Vec<Range<usize>> {
    if f.rods.is_empty() {
        return std::iter::once(0..f.points.len()).collect();
    }
    let mut start = 0;
    (f.rods.iter())
        .map(|&n| {
            start += n;
            start - n..start
        })
        .collect()
}

/// The snapshots in time order with their times (s), a snapshot stored twice
/// (one sample under two labels) once. Snapshots stored before their time was
/// recorded go by falling l_k bar, numbered 0, 1, 2, ... for time.
fn in_time(snapshots: &[Snapshot]) -> Vec<(f64, &Snapshot)> {
    let timed = snapshots.iter().any(|f| f.time > 0.0);
    let mut list: Vec<&Snapshot> = snapshots.iter().collect();
    if timed {
        list.sort_by(|a, b| a.time.total_cmp(&b.time));
    } else {
        list.sort_by(|a, b| b.l_k_bar.total_cmp(&a.l_k_bar));
    }
    list.dedup_by(|a, b| a.time == b.time && a.l_k_bar == b.l_k_bar);
    list.into_iter()
        .enumerate()
        .map(|(k, f)| (if timed { f.time } else { k as f64 }, f))
        .collect()
}

/// Whole-file values of a snapshot at `time`.
fn field_data<'a>(time: &'a [f64; 1], l_k_bar: &'a [f64; 1]) -> [Array<'a>; 2] {
    [
        Array::scalars("TimeValue", Values::F64(time)),
        Array::scalars("l_k_bar", Values::F64(l_k_bar)),
    ]
}

/// The centre line of the rod of `f` whose nodes are `nodes`; per-node
/// fields it lacks (a snapshot stored before they were recorded) are left
/// out.
fn centreline(f: &Snapshot, nodes: Range<usize>, radius: f64, time: f64) -> String {
    let n = nodes.len();
    let radii = vec![radius; n];
    let of = |len: usize| (len == f.points.len()).then(|| nodes.clone());
    let mut point_data = vec![Array::scalars("radius", Values::F64(&radii))];
    if let Some(r) = of(f.curvature.len()) {
        point_data.insert(0, Array::scalars("curvature", Values::F32(&f.curvature[r])));
    }
    if let Some(r) = of(f.twist_rate.len()) {
        point_data.push(Array::scalars("twist_rate", Values::F32(&f.twist_rate[r])));
    }
    let velocity: Vec<f32> = of(f.velocity.len())
        .map(|r| f.velocity[r].iter().flatten().copied().collect())
        .unwrap_or_default();
    if !velocity.is_empty() {
        point_data.push(Array::vectors("velocity", Values::F32(&velocity)));
    }
    let (t, l) = ([time], [f.l_k_bar]);
    let fields = field_data(&t, &l);
    xml::poly_data(&f.points[nodes], Cells::Polyline, &point_data, &fields)
}

/// The loaded contacts of `f`.
fn contacts(f: &Snapshot, time: f64) -> String {
    let points: Vec<[f64; 3]> = f
        .contacts
        .iter()
        .map(|c| std::array::from_fn(|i| 0.5 * (c.a[i] + c.b[i])))
        .collect();
    let normal: Vec<f64> = f.contacts.iter().flat_map(|c| c.normal_force).collect();
    let friction: Vec<f64> = f.contacts.iter().flat_map(|c| c.friction_force).collect();
    let stick: Vec<i32> = f.contacts.iter().map(|c| i32::from(c.stick)).collect();
    let point_data = [
        Array::scalars("stick", Values::I32(&stick)),
        Array::vectors("normal_force", Values::F64(&normal)),
        Array::vectors("friction_force", Values::F64(&friction)),
    ];
    let (t, l) = ([time], [f.l_k_bar]);
    let fields = field_data(&t, &l);
    xml::poly_data(&points, Cells::Vertices, &point_data, &fields)
}

#[cfg(test)]
mod tests {
    use super::case_files;
    use solver::protocol::{Snapshot, SnapshotContact};

    /// A snapshot of `n` nodes along x at `time`, with one sticking contact.
    fn snapshot(label: &str, time: f64, l_k_bar: f64, n: usize) -> Snapshot {
        Snapshot {
            label: label.parse().expect("a snapshot label"),
            l_k_bar,
            time,
            points: (0..n).map(|i| [i as f64 * 1e-2, 0.0, 0.0]).collect(),
            twist_rate: vec![1.5; n],
            curvature: vec![0.25; n],
            velocity: vec![[0.0, 1e-3, 0.0]; n],
            contacts: vec![SnapshotContact {
                a: [0.0, 0.0, 1e-3],
                b: [0.0, 0.0, -1e-3],
                force: 1.0,
                normal_force: [0.0, 0.0, 1.0],
                friction_force: [0.05, 0.0, 0.0],
                stick: true,
            }],
            rods: Vec::new(),
        }
    }

    /// `text`'s `DataArray`s by name, with their values.
    fn arrays(text: &str) -> Vec<(String, Vec<f64>)> {
        let doc = roxmltree::Document::parse(text).expect("well-formed XML");
        doc.descendants()
            .filter(|e| e.has_tag_name("DataArray"))
            .map(|e| {
                let values = e.text().unwrap_or("").split_whitespace();
                let values = values.map(|v| v.parse().expect("a number")).collect();
                (e.attribute("Name").unwrap_or("").to_string(), values)
            })
            .collect()
    }

    fn piece_attribute(text: &str, name: &str) -> usize {
        let doc = roxmltree::Document::parse(text).unwrap();
        let piece = doc.descendants().find(|e| e.has_tag_name("Piece")).unwrap();
        piece.attribute(name).unwrap().parse().unwrap()
    }

    #[test]
    fn one_polyline_and_the_contacts_per_snapshot_in_time_order() {
        let snapshots = [
            snapshot("pull", 2.0, 140.0, 5),
            snapshot("relaxed", 1.0, 160.0, 5),
            snapshot("at_inversion", 2.0, 140.0, 5),
        ];
        let files = case_files("case", 1.6e-3, &snapshots);
        let paths: Vec<&str> = files.iter().map(|f| f.path.as_str()).collect();
        assert_eq!(
            paths,
            [
                "case.pvd",
                "case/centreline_000.vtp",
                "case/contacts_000.vtp",
                "case/centreline_001.vtp",
                "case/contacts_001.vtp"
            ]
        );
        let pvd = roxmltree::Document::parse(&files[0].text).expect("well-formed XML");
        let sets: Vec<(f64, &str)> = pvd
            .descendants()
            .filter(|e| e.has_tag_name("DataSet"))
            .map(|e| {
                (
                    e.attribute("timestep").unwrap().parse().unwrap(),
                    e.attribute("file").unwrap(),
                )
            })
            .collect();
        assert_eq!(sets.len(), 4);
        assert_eq!(sets[0], (1.0, "case/centreline_000.vtp"));
        assert_eq!(sets[3], (2.0, "case/contacts_001.vtp"));

        let line = &files[1].text;
        assert_eq!(piece_attribute(line, "NumberOfPoints"), 5);
        assert_eq!(piece_attribute(line, "NumberOfLines"), 1);
        let a = arrays(line);
        let get = |name: &str| &a.iter().find(|(n, _)| n == name).expect(name).1;
        assert_eq!(get("radius"), &vec![1.6e-3; 5]);
        assert_eq!(get("curvature").len(), 5);
        assert_eq!(get("twist_rate")[4], 1.5);
        assert_eq!(get("velocity").len(), 15);
        assert_eq!(get("connectivity"), &vec![0.0, 1.0, 2.0, 3.0, 4.0]);
        assert_eq!(get("offsets"), &vec![5.0]);
        assert_eq!(get("TimeValue"), &vec![1.0]);
        assert_eq!(get("l_k_bar"), &vec![160.0]);

        let contacts = &files[2].text;
        assert_eq!(piece_attribute(contacts, "NumberOfVerts"), 1);
        let a = arrays(contacts);
        let get = |name: &str| &a.iter().find(|(n, _)| n == name).expect(name).1;
        assert_eq!(get("Points"), &vec![0.0; 3]);
        assert_eq!(get("normal_force"), &vec![0.0, 0.0, 1.0]);
        assert_eq!(get("friction_force"), &vec![0.05, 0.0, 0.0]);
        assert_eq!(get("stick"), &vec![1.0]);
    }

    /// A bend's snapshot: a block per rod (its own nodes and fields), then
    /// the contacts.
    #[test]
    fn a_bend_gets_a_block_per_rod() {
        let mut bend = snapshot("relaxed", 1.0, 160.0, 7);
        bend.rods = vec![3, 4];
        bend.curvature = (0..7).map(|i| i as f32).collect();
        let files = case_files("bend", 1e-3, &[bend]);
        let paths: Vec<&str> = files.iter().map(|f| f.path.as_str()).collect();
        assert_eq!(
            paths,
            [
                "bend.pvd",
                "bend/rod_0_000.vtp",
                "bend/rod_1_000.vtp",
                "bend/contacts_000.vtp"
            ]
        );
        let pvd = roxmltree::Document::parse(&files[0].text).unwrap();
        let sets: Vec<(&str, &str)> = pvd
            .descendants()
            .filter(|e| e.has_tag_name("DataSet"))
            .map(|e| (e.attribute("part").unwrap(), e.attribute("name").unwrap()))
            .collect();
        assert_eq!(sets, [("0", "rod_0"), ("1", "rod_1"), ("2", "contacts")]);
        for (file, first, n) in [(1, 0.0, 3), (2, 3.0, 4)] {
            let text = &files[file].text;
            assert_eq!(piece_attribute(text, "NumberOfPoints"), n);
            assert_eq!(piece_attribute(text, "NumberOfLines"), 1);
            let a = arrays(text);
            let get = |name: &str| &a.iter().find(|(m, _)| m == name).expect(name).1;
            assert_eq!(get("curvature")[0], first);
            assert_eq!(get("Points")[0], first * 1e-2);
            assert_eq!(get("velocity").len(), 3 * n);
        }
    }

    #[test]
    fn snapshots_stored_before_times_and_fields_go_by_l_k_bar() {
        let mut old = [
            snapshot("pull", 0.0, 120.0, 4),
            snapshot("relaxed", 0.0, 160.0, 4),
        ];
        for f in &mut old {
            (f.twist_rate, f.curvature, f.velocity) = (Vec::new(), Vec::new(), Vec::new());
        }
        let files = case_files("old", 1e-3, &old);
        assert!(files[0].text.contains("relaxed: l_k bar 160.00"));
        let pvd = roxmltree::Document::parse(&files[0].text).unwrap();
        let times: Vec<&str> = pvd
            .descendants()
            .filter_map(|e| e.attribute("timestep"))
            .collect();
        assert_eq!(times, ["0e0", "0e0", "1e0", "1e0"]);
        let names: Vec<String> = arrays(&files[1].text).into_iter().map(|(n, _)| n).collect();
        assert_eq!(
            names,
            [
                "TimeValue",
                "l_k_bar",
                "radius",
                "Points",
                "connectivity",
                "offsets"
            ]
        );
    }
}

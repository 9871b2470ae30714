//! The VTK XML formats written here, ASCII: PolyData (`.vtp`) with point
//! and field data, and the Collection (`.pvd`) that orders files in time.
use std::fmt::Write;

/// Numbers of a data array.
pub enum Values<'a> {
    F64(&'a [f64]),
    F32(&'a [f32]),
    I32(&'a [i32]),
}

/// A named data array of `components` values per tuple.
pub struct Array<'a> {
    pub name: &'a str,
    pub components: usize,
    pub values: Values<'a>,
}

impl<'a> Array<'a> {
    pub fn scalars(name: &'a str, values: Values<'a>) -> Self {
        Self {
            name,
            components: 1,
            values,
        }
    }

    pub fn vectors(name: &'a str, values: Values<'a>) -> Self {
        Self {
            name,
            components: 3,
            values,
        }
    }

    /// The array's number of values.
    fn len(&self) -> usize {
        match self.values {
            Values::F64(v) => v.len(),
            Values::F32(v) => v.len(),
            Values::I32(v) => v.len(),
        }
    }

    fn write(&self, out: &mut String, indent: &str) {
        let kind = match self.values {
            Values::F64(_) => "Float64",
            Values::F32(_) => "Float32",
            Values::I32(_) => "Int32",
        };
        let _ = write!(
            out,
            "{indent}<DataArray type=\"{kind}\" Name=\"{}\" NumberOfComponents=\"{}\" \
             NumberOfTuples=\"{}\" format=\"ascii\">",
            escape(self.name),
            self.components,
            self.len() / self.components
        );
        match self.values {
            Values::F64(v) => join(out, v, |out, x| write!(out, "{x:e}")),
            Values::F32(v) => join(out, v, |out, x| write!(out, "{x:e}")),
            Values::I32(v) => join(out, v, |out, x| write!(out, "{x}")),
        }
        out.push_str("</DataArray>\n");
    }
}

/// How the points of a piece are joined into cells.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum Cells {
    /// One polyline through every point, in order.
    Polyline,
    /// A vertex cell per point.
    Vertices,
}

/// A PolyData file of `points` (m) joined by `cells`, with `point_data`
/// (one tuple per point; the first scalar and first vector arrays are the
/// active ones) and `field_data` (whole-file values).
pub fn poly_data(points: &[[f64; 3]], cells: Cells, point_data: &[Array], field_data: &[Array]) -> String {
    let n = points.len();
    let mut out = String::from(
        "<?xml version=\"1.0\"?>\n\
         <VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n<PolyData>\n",
    );
    if !field_data.is_empty() {
        out.push_str("<FieldData>\n");
        for a in field_data {
            a.write(&mut out, "  ");
        }
        out.push_str("</FieldData>\n");
    }
    let (verts, lines) = match cells {
        Cells::Polyline if n > 0 => (0, 1),
        Cells::Polyline => (0, 0),
        Cells::Vertices => (n, 0),
    };
    let _ = writeln!(
        out,
        "<Piece NumberOfPoints=\"{n}\" NumberOfVerts=\"{verts}\" NumberOfLines=\"{lines}\" \
         NumberOfStrips=\"0\" NumberOfPolys=\"0\">"
    );
    let active = |components: usize| {
        point_data
            .iter()
            .find(|a| a.components == components)
            .map(|a| escape(a.name))
    };
    out.push_str("<PointData");
    if let Some(name) = active(1) {
        let _ = write!(out, " Scalars=\"{name}\"");
    }
    if let Some(name) = active(3) {
        let _ = write!(out, " Vectors=\"{name}\"");
    }
    out.push_str(">\n");
    for a in point_data {
        debug_assert_eq!(a.len(), n * a.components, "{}", a.name);
        a.write(&mut out, "  ");
    }
    out.push_str("</PointData>\n<Points>\n");
    let flat: Vec<f64> = points.iter().flatten().copied().collect();
    Array::vectors("Points", Values::F64(&flat)).write(&mut out, "  ");
    out.push_str("</Points>\n");
    let connectivity: Vec<i32> = (0..n as i32).collect();
    let (element, offsets): (&str, Vec<i32>) = match cells {
        Cells::Polyline => ("Lines", if n > 0 { vec![n as i32] } else { Vec::new() }),
        Cells::Vertices => ("Verts", (1..=n as i32).collect()),
    };
    let _ = writeln!(out, "<{element}>");
    Array::scalars("connectivity", Values::I32(&connectivity)).write(&mut out, "  ");
    Array::scalars("offsets", Values::I32(&offsets)).write(&mut out, "  ");
    let _ = writeln!(out, "</{element}>\n</Piece>\n</PolyData>\n</VTKFile>");
    out
}

/// A file of a [`collection`]: its time (s), part number, part name, path
/// relative to the `.pvd`, and a comment written before it.
pub struct DataSet<'a> {
    pub timestep: f64,
    pub part: usize,
    pub name: &'a str,
    pub file: &'a str,
    pub comment: &'a str,
}

/// A Collection (`.pvd`) of `datasets`, in the order given.
pub fn collection(datasets: &[DataSet]) -> String {
    let mut out = String::from(
        "<?xml version=\"1.0\"?>\n\
         <VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n<Collection>\n",
    );
    for d in datasets {
        if !d.comment.is_empty() {
            let _ = writeln!(out, "  <!-- {} -->", d.comment.replace("--", "- -"));
        }
        let _ = writeln!(
            out,
            "  <DataSet timestep=\"{:e}\" group=\"\" part=\"{}\" name=\"{}\" file=\"{}\"/>",
            d.timestep,
            d.part,
            escape(d.name),
            escape(d.file)
        );
    }
    out.push_str("</Collection>\n</VTKFile>\n");
    out
}

/// `items`, each written by `item`, separated by spaces.
fn join<T>(out: &mut String, items: &[T], item: impl Fn(&mut String, &T) -> std::fmt::Result) {
    for (i, x) in items.iter().enumerate() {
        if i > 0 {
            out.push(' ');
        }
        let _ = item(out, x);
    }
}

/// `text` safe inside an XML attribute.
fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

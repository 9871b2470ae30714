//! Charts as PDF, for journals: a chart's SVG (the few elements plotters'
//! SVG backend writes: `rect`, `line`, `polyline`, `polygon`, `circle`,
//! `text`) redrawn as vector PDF operators on one page, the text in the
//! standard Helvetica and Symbol fonts (no font files, nothing embedded).
//! The paper's symbols come through: Greek letters from Symbol, a combining
//! macron (l̄_k, F̄) as a bar drawn over its letter.
use anyhow::{Context, Result, bail};
use std::fmt::Write;

/// Helvetica's advance widths (per 1000 em) of the printable ASCII
/// characters, 32 to 126 (Adobe's font metrics).
const HELVETICA: [u16; 95] = [
    278, 278, 355, 556, 556, 889, 667, 191, 333, 333, 389, 584, 278, 333, 278, 278, 556, 556, 556, 556, 556,
    556, 556, 556, 556, 556, 278, 278, 584, 584, 584, 556, 1015, 667, 667, 722, 722, 667, 611, 778, 722, 278,
    500, 667, 556, 833, 722, 778, 667, 778, 722, 667, 611, 722, 667, 944, 667, 667, 611, 278, 278, 278, 469,
    556, 333, 556, 556, 500, 556, 556, 278, 556, 556, 222, 222, 500, 222, 833, 556, 556, 556, 556, 333, 500,
    278, 556, 500, 722, 500, 500, 500, 334, 260, 334, 584,
];

/// A run of text in one font: `F1` Helvetica (WinAnsi bytes) or `F2` Symbol.
#[derive(Debug, PartialEq)]
struct Glyph {
    symbol: bool,
    byte: u8,
    /// Advance width per 1000 em.
    width: f64,
    /// A bar over it (a combining macron followed it).
    bar: bool,
}

/// The glyphs of `text`: Latin-1 characters in Helvetica, Greek letters in
/// Symbol, a few signs spelled in ASCII; a combining macron bars the glyph
/// before it.
fn glyphs(text: &str) -> Vec<Glyph> {
    let mut out: Vec<Glyph> = Vec::new();
    for c in text.chars() {
        let helvetica = |byte: u8, width: f64| Glyph {
            symbol: false,
            byte,
            width,
            bar: false,
        };
        let symbol = |byte: u8| Glyph {
            symbol: true,
            byte,
            width: 576.0,
            bar: false,
        };
        let spelled = |s: &str| {
            s.bytes()
                .map(|b| helvetica(b, f64::from(HELVETICA[(b - 32) as usize])))
                .collect::<Vec<_>>()
        };
        match c {
            '\u{0304}' => {
                if let Some(last) = out.last_mut() {
                    last.bar = true;
                }
            }
            ' '..='~' => out.push(helvetica(c as u8, f64::from(HELVETICA[c as usize - 32]))),
            'μ' | 'µ' => out.push(helvetica(0xB5, 556.0)),
            '²' => out.push(helvetica(0xB2, 333.0)),
            '³' => out.push(helvetica(0xB3, 333.0)),
            '±' => out.push(helvetica(0xB1, 584.0)),
            '×' => out.push(helvetica(0xD7, 584.0)),
            '·' => out.push(helvetica(0xB7, 278.0)),
            'ρ' => out.push(symbol(b'r')),
            'ν' => out.push(symbol(b'n')),
            'ε' => out.push(symbol(b'e')),
            'φ' => out.push(symbol(b'f')),
            'δ' => out.push(symbol(b'd')),
            'Δ' => out.push(symbol(b'D')),
            'χ' => out.push(symbol(b'c')),
            'θ' => out.push(symbol(b'q')),
            '−' | '–' => out.extend(spelled("-")),
            '→' => out.extend(spelled("->")),
            _ => out.extend(spelled("?")),
        }
    }
    out
}

/// The width of `text` at `size` (the unit of `size`).
fn text_width(glyphs: &[Glyph], size: f64) -> f64 {
    glyphs.iter().map(|g| g.width).sum::<f64>() * size / 1000.0
}

/// An element's attribute, unescaped.
fn attribute<'a>(tag: &'a str, name: &str) -> Option<&'a str> {
    let key = format!(" {name}=\"");
    let start = tag.find(&key)? + key.len();
    let end = tag[start..].find('"')? + start;
    Some(&tag[start..end])
}

fn number(tag: &str, name: &str) -> Result<f64> {
    attribute(tag, name)
        .with_context(|| format!("no {name} in {tag}"))?
        .parse()
        .with_context(|| format!("{name} of {tag}"))
}

/// `#RRGGBB` as PDF's 0..1 components, blended with the white page by `opacity`.
fn colour(value: &str, opacity: f64) -> Option<[f64; 3]> {
    let hex = value.strip_prefix('#')?;
    let channel = |i: usize| u8::from_str_radix(hex.get(i..i + 2)?, 16).ok();
    let rgb = [channel(0)?, channel(2)?, channel(4)?];
    Some(rgb.map(|c| 1.0 - opacity * (1.0 - f64::from(c) / 255.0)))
}

/// `points="x,y x,y ..."` as pairs.
fn points(tag: &str) -> Result<Vec<(f64, f64)>> {
    let text = attribute(tag, "points").context("no points")?;
    text.split_whitespace()
        .map(|p| {
            let (x, y) = p.split_once(',').context("a point x,y")?;
            Ok((x.parse()?, y.parse()?))
        })
        .collect()
}

fn unescape(text: &str) -> String {
    text.replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&quot;", "\"")
        .replace("&apos;", "'")
        .replace("&#39;", "'")
        .replace("&amp;", "&")
}

/// A string of PDF bytes: `(...)` with its parentheses and backslashes escaped.
fn pdf_string(bytes: impl Iterator<Item = u8>) -> String {
    let mut s = String::from("(");
    for b in bytes {
        match b {
            b'(' | b')' | b'\\' => {
                s.push('\\');
                s.push(b as char);
            }
            32..=126 => s.push(b as char),
            _ => {
                let _ = write!(s, "\\{b:03o}");
            }
        }
    }
    s.push(')');
    s
}

/// The page's drawing operators for the SVG's elements (in the SVG's pixel
/// coordinates, y down: the page's matrix flips them).
fn content(svg: &str, height: f64) -> Result<String> {
    let mut out = format!("1 0 0 -1 0 {height} cm 1 J 1 j\n");
    let mut rest = svg;
    while let Some(open) = rest.find('<') {
        rest = &rest[open..];
        let close = rest.find('>').context("an unclosed tag")?;
        let tag = &rest[..=close];
        rest = &rest[close + 1..];
        let name = tag[1..].split([' ', '>', '/']).next().unwrap_or_default();
        let opacity = attribute(tag, "opacity")
            .and_then(|o| o.parse().ok())
            .unwrap_or(1.0);
        let fill = attribute(tag, "fill").and_then(|c| colour(c, opacity));
        let stroke = attribute(tag, "stroke").and_then(|c| colour(c, opacity));
        let width = attribute(tag, "stroke-width")
            .and_then(|w| w.parse().ok())
            .unwrap_or(1.0);
        let paint = |out: &mut String, path: &str| {
            if let Some([r, g, b]) = fill {
                let _ = writeln!(out, "{r:.4} {g:.4} {b:.4} rg");
            }
            if let Some([r, g, b]) = stroke {
                let _ = writeln!(out, "{r:.4} {g:.4} {b:.4} RG {width} w");
            }
            let op = match (fill.is_some(), stroke.is_some()) {
                (true, true) => "B",
                (true, false) => "f",
                (false, true) => "S",
                (false, false) => "n",
            };
            let _ = writeln!(out, "{path}{op}");
        };
        match name {
            "rect" => {
                let (x, y, w, h) = (
                    number(tag, "x")?,
                    number(tag, "y")?,
                    number(tag, "width")?,
                    number(tag, "height")?,
                );
                paint(&mut out, &format!("{x} {y} {w} {h} re "));
            }
            "line" => {
                let path = format!(
                    "{} {} m {} {} l ",
                    number(tag, "x1")?,
                    number(tag, "y1")?,
                    number(tag, "x2")?,
                    number(tag, "y2")?
                );
                paint(&mut out, &path);
            }
            "polyline" | "polygon" => {
                let mut path = String::new();
                for (k, (x, y)) in points(tag)?.into_iter().enumerate() {
                    let _ = write!(path, "{x} {y} {} ", if k == 0 { "m" } else { "l" });
                }
                if name == "polygon" {
                    path.push_str("h ");
                }
                paint(&mut out, &path);
            }
            "circle" => {
                let (x, y, r) = (number(tag, "cx")?, number(tag, "cy")?, number(tag, "r")?);
                // Four Bézier quarters (k: the control points' distance for a circle).
                let k = 0.5523 * r;
                let path = format!(
                    "{} {y} m {} {} {} {} {x} {} c {} {} {} {} {} {y} c {} {} {} {} {x} {} c {} {} {} {} {} {y} c ",
                    x + r,
                    x + r,
                    y + k,
                    x + k,
                    y + r,
                    y + r,
                    x - k,
                    y + r,
                    x - r,
                    y + k,
                    x - r,
                    x - r,
                    y - k,
                    x - k,
                    y - r,
                    y - r,
                    x + k,
                    y - r,
                    x + r,
                    y - k,
                    x + r
                );
                paint(&mut out, &path);
            }
            "text" => {
                let end = rest.find("</text>").context("an unclosed text")?;
                let text = unescape(rest[..end].trim());
                rest = &rest[end + "</text>".len()..];
                write_text(&mut out, tag, &text, fill.unwrap_or([0.0; 3]))?;
            }
            _ => {}
        }
    }
    Ok(out)
}

/// A `text` element: its glyphs placed by its anchor and baseline shift,
/// turned by its rotation, bars drawn over barred letters.
fn write_text(out: &mut String, tag: &str, text: &str, [r, g, b]: [f64; 3]) -> Result<()> {
    let (x, y, size) = (number(tag, "x")?, number(tag, "y")?, number(tag, "font-size")?);
    let glyphs = glyphs(text);
    let width = text_width(&glyphs, size);
    let dx = match attribute(tag, "text-anchor") {
        Some("middle") => -width / 2.0,
        Some("end") => -width,
        _ => 0.0,
    };
    // The SVG's baseline shifts (plotters: 0.76em top, 0.5ex centre, -0.5ex bottom; ex ~ half an em).
    let dy = match attribute(tag, "dy") {
        Some("0.76em") => 0.76 * size,
        Some("0.5ex") => 0.25 * size,
        Some("-0.5ex") => -0.25 * size,
        _ => 0.0,
    };
    let angle = attribute(tag, "transform")
        .and_then(|t| t.strip_prefix("rotate("))
        .and_then(|t| t.split(',').next())
        .and_then(|a| a.trim().parse::<f64>().ok())
        .unwrap_or(0.0)
        .to_radians();
    let (cos, sin) = (angle.cos(), angle.sin());
    // Text space (y up) to the page's flipped space, turned by the angle.
    let to_page = |tx: f64, ty: f64| (x + cos * tx + sin * ty, y + sin * tx - cos * ty);
    let (ox, oy) = (dx, -dy);
    let _ = writeln!(
        out,
        "BT {r:.4} {g:.4} {b:.4} rg {cos:.6} {sin:.6} {sin:.6} {:.6} {x} {y} Tm {ox:.3} {oy:.3} Td",
        -cos
    );
    let mut start = 0;
    while start < glyphs.len() {
        let font = glyphs[start].symbol;
        let end = (start..glyphs.len())
            .find(|&i| glyphs[i].symbol != font)
            .unwrap_or(glyphs.len());
        let _ = writeln!(
            out,
            "/{} {size} Tf {} Tj",
            if font { "F2" } else { "F1" },
            pdf_string(glyphs[start..end].iter().map(|g| g.byte))
        );
        start = end;
    }
    out.push_str("ET\n");
    let mut advance = ox;
    for glyph in &glyphs {
        let w = glyph.width * size / 1000.0;
        if glyph.bar {
            let top = oy + 0.78 * size;
            let (a, z) = (to_page(advance + 0.1 * w, top), to_page(advance + 0.9 * w, top));
            let _ = writeln!(
                out,
                "{r:.4} {g:.4} {b:.4} RG {:.3} w {:.3} {:.3} m {:.3} {:.3} l S",
                0.06 * size,
                a.0,
                a.1,
                z.0,
                z.1
            );
        }
        advance += w;
    }
    Ok(())
}

/// The SVG of a chart (plotters' SVG backend) as a one-page PDF of the same
/// size (a pixel a point), vector throughout.
pub fn svg_to_pdf(svg: &str) -> Result<Vec<u8>> {
    let head = svg.find("<svg").context("not an SVG")?;
    let tag = &svg[head..head + svg[head..].find('>').context("an unclosed svg tag")?];
    let (width, height) = (number(tag, "width")?, number(tag, "height")?);
    if !(width > 0.0 && height > 0.0) {
        bail!("an SVG of size {width} x {height}");
    }
    let stream = content(svg, height)?;
    let objects = [
        "<< /Type /Catalog /Pages 2 0 R >>".to_string(),
        "<< /Type /Pages /Kids [3 0 R] /Count 1 >>".to_string(),
        format!(
            "<< /Type /Page /Parent 2 0 R /MediaBox [0 0 {width} {height}] /Contents 4 0 R \
             /Resources << /Font << /F1 5 0 R /F2 6 0 R >> >> >>"
        ),
        format!("<< /Length {} >>\nstream\n{stream}endstream", stream.len()),
        "<< /Type /Font /Subtype /Type1 /BaseFont /Helvetica /Encoding /WinAnsiEncoding >>".to_string(),
        "<< /Type /Font /Subtype /Type1 /BaseFont /Symbol >>".to_string(),
    ];
    let mut pdf = String::from("%PDF-1.4\n");
    let mut offsets = Vec::new();
    for (k, object) in objects.iter().enumerate() {
        offsets.push(pdf.len());
        let _ = write!(pdf, "{} 0 obj\n{object}\nendobj\n", k + 1);
    }
    let xref = pdf.len();
    let _ = write!(pdf, "xref\n0 {}\n0000000000 65535 f \n", objects.len() + 1);
    for offset in offsets {
        let _ = writeln!(pdf, "{offset:010} 00000 n ");
    }
    let _ = write!(
        pdf,
        "trailer\n<< /Size {} /Root 1 0 R >>\nstartxref\n{xref}\n%%EOF\n",
        objects.len() + 1
    );
    Ok(pdf.into_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    const SVG: &str = r##"<svg width="200" height="100" viewBox="0 0 200 100" xmlns="http://www.w3.org/2000/svg">
<rect x="0" y="0" width="200" height="100" opacity="1" fill="#FFFFFF" stroke="none"/>
<line opacity="1" stroke="#000000" stroke-width="1" x1="10" y1="90" x2="190" y2="90"/>
<polyline fill="none" opacity="1" stroke="#1F77B4" stroke-width="2" points="10,90 50,40 90,60 "/>
<circle cx="50" cy="40" r="5" opacity="1" fill="#D62728" stroke="none" stroke-width="1"/>
<text x="100" y="20" dy="0.76em" text-anchor="middle" font-family="sans-serif" font-size="16.129" opacity="1" fill="#000000">
F̄ against l̄_k (μ = 0.1, ρ &amp; ν)
</text>
<text x="8" y="50" dy="0.5ex" text-anchor="middle" font-family="sans-serif" font-size="12" opacity="1" fill="#000000" transform="rotate(270, 8, 50)">
H̄ = H / W
</text>
</svg>"##;

    #[test]
    fn the_cross_reference_table_points_at_every_object() {
        let pdf = String::from_utf8(svg_to_pdf(SVG).unwrap()).unwrap();
        assert!(pdf.starts_with("%PDF-1.4\n") && pdf.ends_with("%%EOF\n"));
        let xref: usize = pdf
            .rsplit("startxref\n")
            .next()
            .unwrap()
            .lines()
            .next()
            .unwrap()
            .parse()
            .unwrap();
        assert!(pdf[xref..].starts_with("xref\n0 7\n"));
        let offsets: Vec<usize> = pdf[xref..]
            .lines()
            .skip(3)
            .take(6)
            .map(|l| l[..10].parse().unwrap())
            .collect();
        for (k, offset) in offsets.iter().enumerate() {
            assert!(
                pdf[*offset..].starts_with(&format!("{} 0 obj\n", k + 1)),
                "object {}",
                k + 1
            );
        }
        let length: usize = pdf
            .split("/Length ")
            .nth(1)
            .unwrap()
            .split(' ')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        let stream = pdf.split_once(">>\nstream\n").unwrap().1;
        assert_eq!(
            &stream[length..length + "endstream".len()],
            "endstream",
            "the stream's length"
        );
        assert!(pdf.contains("/MediaBox [0 0 200 100]"));
    }

    #[test]
    fn every_element_is_drawn_and_the_symbols_come_through() {
        let pdf = String::from_utf8(svg_to_pdf(SVG).unwrap()).unwrap();
        let ops = |op: &str| pdf.lines().filter(|l| l.ends_with(op)).count();
        assert_eq!(ops(" re f"), 1, "the background");
        assert_eq!(ops(" c B") + ops(" c f"), 1, "the circle");
        assert_eq!(pdf.matches("BT ").count(), 2, "two texts");
        // F and l barred (two bars), mu from Helvetica's Latin-1, rho and nu from Symbol.
        assert_eq!(
            pdf.matches("RG 0.968 w").count(),
            2,
            "the bars of F and l in the title"
        );
        assert_eq!(
            pdf.matches("RG 0.720 w").count(),
            1,
            "the bar of H in the axis label"
        );
        assert!(
            pdf.contains("/F1 16.129 Tf (F against l_k \\(\\265 = 0.1, ) Tj"),
            "{pdf}"
        );
        assert!(pdf.contains("/F2 16.129 Tf (r) Tj"));
        // The rotated label: the text matrix turned by 270 degrees.
        assert!(
            pdf.contains("-0.000000 -1.000000 -1.000000 0.000000 8 50 Tm"),
            "{pdf}"
        );
    }

    #[test]
    fn widths_are_helveticas() {
        assert_eq!(text_width(&glyphs("l"), 1000.0), 222.0);
        assert_eq!(
            text_width(&glyphs("F̄"), 1000.0),
            611.0,
            "the macron takes no room"
        );
        assert!(glyphs("F̄")[0].bar);
    }
}

//! The knot drawn as the paper's Fig. 1 frames its photographs, for
//! `knotsweep snapshots`: the pull horizontal, the rod with its true radius.
use anyhow::{Result, anyhow};
use nalgebra::Vector3;
use plotters::prelude::*;

/// The knot seen along the direction in which it is thinnest (the loop
/// faces the viewer, as in the paper's photographs), the pull axis x
/// horizontal, framed on the knot; the stroke is 2h wide (h the rod's radius).
pub fn side_view(points: &[Vector3<f64>], h: f64, title: &str) -> Result<String> {
    let centre = points.iter().sum::<Vector3<f64>>() / points.len() as f64;
    // The in-plane vertical axis: the direction across x in which the knot spreads most.
    let (mut syy, mut syz, mut szz) = (0.0, 0.0, 0.0);
    for p in points {
        let d = p - centre;
        syy += d.y * d.y;
        syz += d.y * d.z;
        szz += d.z * d.z;
    }
    let angle = 0.5 * (2.0 * syz).atan2(syy - szz);
    let up = Vector3::new(0.0, angle.cos(), angle.sin());
    // Frame the knot: the nodes off the pull axis by more than 3h (the tails
    // lie on it), with a margin of a fifth of their extent.
    let (first, last) = (points[0], points[points.len() - 1]);
    let axis = (last - first).normalize();
    let off_axis = |p: &Vector3<f64>| {
        let d = p - first;
        (d - axis * d.dot(&axis)).norm() > 3.0 * h
    };
    let (lo, hi) = points
        .iter()
        .filter(|p| off_axis(p))
        .map(|p| (p - centre).x)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        });
    let centre = if lo.is_finite() {
        centre + Vector3::x() * (0.5 * (lo + hi))
    } else {
        centre
    };
    let half_width = if lo.is_finite() { 0.6 * (hi - lo) } else { 0.06 }.max(20.0 * h);
    let (width_px, height_px) = (900u32, 540u32);
    let half_height = half_width * f64::from(height_px) / f64::from(width_px);
    let scale = f64::from(width_px) / (2.0 * half_width);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (width_px, height_px + 40)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| anyhow!("{e}"))?;
        let (top, body) = root.split_vertically(40);
        top.titled(title, ("sans-serif", 20))
            .map_err(|e| anyhow!("{e}"))?;
        let to_px = |p: &Vector3<f64>| {
            let d = p - centre;
            let x = (d.x + half_width) * scale;
            let y = (half_height - d.dot(&up)) * scale;
            (x.round() as i32, y.round() as i32)
        };
        let stroke = ((2.0 * h * scale).round() as u32).max(1);
        let path: Vec<(i32, i32)> = points.iter().map(to_px).collect();
        body.draw(&PathElement::new(path.clone(), BLACK.stroke_width(stroke + 2)))
            .map_err(|e| anyhow!("{e}"))?;
        body.draw(&PathElement::new(
            path,
            RGBColor(220, 120, 40).stroke_width(stroke),
        ))
        .map_err(|e| anyhow!("{e}"))?;
        let bar = (0.01 * scale).round() as i32;
        let y = height_px as i32 - 20;
        body.draw(&PathElement::new(
            vec![(20, y), (20 + bar, y)],
            BLACK.stroke_width(2),
        ))
        .map_err(|e| anyhow!("{e}"))?;
        body.draw(&Text::new("1 cm", (20, y - 18), ("sans-serif", 14)))
            .map_err(|e| anyhow!("{e}"))?;
    }
    Ok(svg)
}

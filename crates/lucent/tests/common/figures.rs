//! The statistics of `validation/validation_stats.py` that the validation tests check (the
//! homogeneous suite's `validation.rs` and HTSM's `htsm_validation.rs`), on the channel sum:
//! the median per-pixel relative error, the bias of the means and the worst 8x8 block beyond
//! twice its Monte Carlo noise, against the mean of two seeded reference halves.

use std::path::Path;

/// RGBA pixels of an EXR, rows top first.
pub fn read_exr(path: &Path) -> (usize, usize, Vec<[f32; 4]>) {
    let img = exr::prelude::read_first_rgba_layer_from_file(
        path,
        |res, _| (res.width(), res.height(), vec![[0.0f32; 4]; res.width() * res.height()]),
        |(w, _, v): &mut (usize, usize, Vec<[f32; 4]>), p, (r, g, b, a): (f32, f32, f32, f32)| {
            v[p.y() * *w + p.x()] = [r, g, b, a]
        },
    )
    .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    img.layer_data.channel_data.pixels
}

/// Fully covered pixels whose four neighbours are too.
pub fn interior(w: usize, h: usize, px: &[[f32; 4]]) -> Vec<bool> {
    let full = |x: usize, y: usize| px[y * w + x][3] > 0.999;
    (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            x > 0
                && y > 0
                && x + 1 < w
                && y + 1 < h
                && full(x, y)
                && full(x - 1, y)
                && full(x + 1, y)
                && full(x, y - 1)
                && full(x, y + 1)
        })
        .collect()
}

/// One image's figures against a reference (fractions, e.g. 0.05 = 5%).
pub struct Figures {
    /// Median per-pixel relative error.
    pub median: f64,
    /// Mean of ours over mean of the reference, minus 1.
    pub bias: f64,
    /// Worst 8x8 block's relative error beyond twice its noise.
    pub worst_block: f64,
}

/// The compare script's statistics on the channel sum (`validation/lucent_validation.py`).
pub fn figures(
    w: usize,
    h: usize,
    ours: &[[f32; 4]],
    a: &[[f32; 4]],
    b: &[[f32; 4]],
    mask: &[bool],
) -> Figures {
    let lum = |p: &[f32; 4]| (p[0] + p[1] + p[2]) as f64;
    let r: Vec<f64> = a.iter().zip(b).map(|(a, b)| 0.5 * (lum(a) + lum(b))).collect();
    let noise: Vec<f64> = a.iter().zip(b).map(|(a, b)| 0.5 * (lum(a) - lum(b)).abs()).collect();
    let o: Vec<f64> = ours.iter().map(lum).collect();
    let sel: Vec<bool> = (0..w * h).map(|i| mask[i] && r[i] > 1e-6).collect();
    let mut rel: Vec<f64> = (0..w * h).filter(|&i| sel[i]).map(|i| (o[i] - r[i]) / r[i]).collect();
    rel.sort_by(|x, y| x.total_cmp(y));
    let median = if rel.is_empty() { f64::NAN } else { rel[rel.len() / 2] };
    let (so, sr) = (0..w * h).filter(|&i| sel[i]).fold((0.0, 0.0), |(so, sr), i| (so + o[i], sr + r[i]));
    let mut worst = 0.0f64;
    for by in (0..h.saturating_sub(7)).step_by(8) {
        for bx in (0..w.saturating_sub(7)).step_by(8) {
            let idx: Vec<usize> =
                (0..64).map(|k| (by + k / 8) * w + bx + k % 8).filter(|&i| sel[i]).collect();
            if idx.len() < 32 {
                continue;
            }
            let n = idx.len() as f64;
            let (mo, mr) =
                (idx.iter().map(|&i| o[i]).sum::<f64>() / n, idx.iter().map(|&i| r[i]).sum::<f64>() / n);
            let nb = idx.iter().map(|&i| noise[i] * noise[i]).sum::<f64>().sqrt() / n;
            worst = worst.max(((mo - mr).abs() - 2.0 * nb).max(0.0) / mr);
        }
    }
    Figures { median, bias: so / sr - 1.0, worst_block: worst }
}

//! Picking a filter per chunk.
//!
//! What matters is the size after zstd, and zstd gains much of its ratio on these residuals from
//! repeats (runs of small residuals along smooth rows), which a sum of residual magnitudes or an
//! order-0 entropy does not see: on the codec bench table choosing by significant bits left 9%
//! (log16) on the table compared with compressing every candidate. So the choice runs in two
//! rounds on a sample of rows (every 4th): all filters are ranked by the order-0 entropy of
//! their residuals' byte planes (cheap: one histogram per plane), and the best [`FINALISTS`] are
//! compressed with zstd at level 1 — within 0.3% of the best by full compression on that table,
//! at the cost of two small zstd calls.

use super::filter::{self, Filter, Layout, Word};

/// How many filters go into the zstd round.
pub const FINALISTS: usize = 2;

/// Rows sampled for the entropy round: every `RANK_EVERY`-th.
const RANK_EVERY: usize = 8;
/// Rows sampled for the zstd round: every `TRIAL_EVERY`-th.
const TRIAL_EVERY: usize = 4;

/// The filters worth trying on `layout` (channel filters only with several channels).
pub fn candidates(layout: Layout) -> impl Iterator<Item = Filter> {
    Filter::ALL
        .into_iter()
        .filter(move |f| layout.channels > 1 || !f.channel())
}

/// Order-0 entropy, in bits, of each byte plane of `words`, summed over the planes.
pub fn plane_entropy<W: Word>(words: &[W]) -> f64 {
    let n = words.len() as f64;
    let mut total = 0.0;
    for k in 0..W::BYTES {
        // Four histograms, so that runs of one byte value do not serialize the increments.
        let mut hist = [[0u32; 256]; 4];
        let mut quads = words.chunks_exact(4);
        for q in &mut quads {
            for (h, w) in hist.iter_mut().zip(q) {
                h[w.byte(k) as usize] += 1;
            }
        }
        for w in quads.remainder() {
            hist[0][w.byte(k) as usize] += 1;
        }
        total += (0..256)
            .map(|b| hist.iter().map(|h| h[b]).sum::<u32>())
            .filter(|&c| c > 0)
            .map(|c| {
                let c = c as f64;
                c * (n / c).log2()
            })
            .sum::<f64>();
    }
    total
}

/// Bytes zstd (level 1) makes of byte-shuffled `words`; `None` if zstd fails.
fn trial_size<W: Word>(words: &[W]) -> Option<usize> {
    let mut b = Vec::with_capacity(words.len() * W::BYTES);
    filter::shuffle(words, &mut b);
    super::zstd_compress(&b, 1).ok().map(|c| c.len())
}

/// Picks the filter whose residuals are likely to compress best (see the module docs).
pub fn choose<W: Word>(words: &[W], layout: Layout) -> Filter {
    let mut r = Vec::new();
    let mut ranked: Vec<(f64, Filter)> = candidates(layout)
        .map(|f| {
            r.clear();
            filter::forward_sample(words, layout, f, RANK_EVERY, &mut r);
            (plane_entropy(&r), f)
        })
        .collect();
    ranked.sort_by(|a, b| a.0.total_cmp(&b.0));
    ranked.truncate(FINALISTS);
    ranked
        .iter()
        .filter_map(|&(_, f)| {
            r.clear();
            filter::forward_sample(words, layout, f, TRIAL_EVERY, &mut r);
            Some((trial_size(&r)?, f))
        })
        .min_by_key(|&(size, _)| size)
        .map_or(ranked[0].1, |(_, f)| f)
}

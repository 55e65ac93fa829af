//! Sequential Monte Carlo with likelihood tempering (Del Moral, Doucet & Jasra 2006), the
//! scheme GrainLearning uses for DEM calibration (Cheng et al. 2019): particles drawn from a
//! uniform prior over the parameter box move through the tempered posteriors
//! prior x likelihood^beta, beta from 0 to 1. Each stage picks beta so that the effective
//! sample size falls to half, resamples (systematic), and moves every particle with a few
//! random-walk Metropolis steps scaled to the particles' spread.

use rand_chacha::ChaCha8Rng;
use rand_chacha::rand_core::{RngCore, SeedableRng};
use serde::Serialize;

/// Metropolis steps per particle and stage.
const MOVES: usize = 6;

/// A posterior sample and its summary.
#[derive(Debug, Clone, Serialize)]
pub struct Posterior {
    #[serde(skip)]
    pub samples: Vec<Vec<f64>>,
    pub mean: Vec<f64>,
    pub sd: Vec<f64>,
    /// 2.5 % and 97.5 % quantiles.
    pub q025: Vec<f64>,
    pub q975: Vec<f64>,
    /// Correlation matrix of the parameters.
    pub correlation: Vec<Vec<f64>>,
    /// Tempering stages taken.
    pub stages: usize,
    /// Mean Metropolis acceptance over all moves.
    pub acceptance: f64,
}

fn uniform(rng: &mut ChaCha8Rng) -> f64 {
    (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64
}

fn normal(rng: &mut ChaCha8Rng) -> f64 {
    // Box-Muller: the sample is reproducible from the seed on every platform.
    let (u, v) = (uniform(rng).max(1e-300), uniform(rng));
    (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
}

fn ess(w: &[f64]) -> f64 {
    let s: f64 = w.iter().sum();
    let s2: f64 = w.iter().map(|v| v * v).sum();
    if s2 > 0.0 { s * s / s2 } else { 0.0 }
}

/// Samples the posterior of `log_like` under a uniform prior on [low, high] with `n`
/// particles; deterministic for a given `seed`.
pub fn smc(
    log_like: impl Fn(&[f64]) -> f64,
    low: &[f64],
    high: &[f64],
    n: usize,
    seed: u64,
) -> Posterior {
    let d = low.len();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut x: Vec<Vec<f64>> = (0..n)
        .map(|_| {
            (0..d)
                .map(|k| low[k] + (high[k] - low[k]) * uniform(&mut rng))
                .collect()
        })
        .collect();
    let mut ll: Vec<f64> = x.iter().map(|p| log_like(p)).collect();
    let mut beta = 0.0;
    let mut stages = 0;
    let (mut accepted, mut tried) = (0usize, 0usize);
    while beta < 1.0 && stages < 200 {
        stages += 1;
        let lmax = ll.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let weights =
            |db: f64| -> Vec<f64> { ll.iter().map(|l| (db * (l - lmax)).exp()).collect() };
        // The largest step in beta that keeps the effective sample size at n / 2.
        let db = if ess(&weights(1.0 - beta)) >= 0.5 * n as f64 {
            1.0 - beta
        } else {
            let (mut lo, mut hi) = (0.0, 1.0 - beta);
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if ess(&weights(mid)) >= 0.5 * n as f64 {
                    lo = mid
                } else {
                    hi = mid
                }
            }
            lo.max(1e-12)
        };
        beta = (beta + db).min(1.0);
        let w = weights(db);
        let total: f64 = w.iter().sum();
        // Systematic resampling.
        let u0 = uniform(&mut rng) / n as f64;
        let mut idx = Vec::with_capacity(n);
        let mut cum = 0.0;
        let mut k = 0;
        for i in 0..n {
            let u = u0 + i as f64 / n as f64;
            while cum + w[k] / total < u && k + 1 < n {
                cum += w[k] / total;
                k += 1;
            }
            idx.push(k);
        }
        x = idx.iter().map(|&i| x[i].clone()).collect();
        ll = idx.iter().map(|&i| ll[i]).collect();
        // Random-walk Metropolis on prior x likelihood^beta, steps scaled to the spread.
        let sd: Vec<f64> = (0..d)
            .map(|k| {
                let m = x.iter().map(|p| p[k]).sum::<f64>() / n as f64;
                let v = x.iter().map(|p| (p[k] - m).powi(2)).sum::<f64>() / n as f64;
                (2.38 / (d as f64).sqrt()) * v.sqrt().max(1e-9 * (high[k] - low[k]))
            })
            .collect();
        for i in 0..n {
            for _ in 0..MOVES {
                let prop: Vec<f64> = (0..d).map(|k| x[i][k] + sd[k] * normal(&mut rng)).collect();
                tried += 1;
                if prop
                    .iter()
                    .zip(low.iter().zip(high))
                    .any(|(v, (l, h))| v < l || v > h)
                {
                    continue;
                }
                let lp = log_like(&prop);
                if (beta * (lp - ll[i])).exp() > uniform(&mut rng) {
                    x[i] = prop;
                    ll[i] = lp;
                    accepted += 1;
                }
            }
        }
    }
    summarise(x, stages, accepted as f64 / tried.max(1) as f64)
}

fn summarise(x: Vec<Vec<f64>>, stages: usize, acceptance: f64) -> Posterior {
    let n = x.len() as f64;
    let d = x.first().map_or(0, Vec::len);
    let mean: Vec<f64> = (0..d)
        .map(|k| x.iter().map(|p| p[k]).sum::<f64>() / n)
        .collect();
    let cov = |a: usize, b: usize| {
        x.iter()
            .map(|p| (p[a] - mean[a]) * (p[b] - mean[b]))
            .sum::<f64>()
            / n
    };
    let sd: Vec<f64> = (0..d).map(|k| cov(k, k).sqrt()).collect();
    let quantile = |k: usize, q: f64| {
        let mut v: Vec<f64> = x.iter().map(|p| p[k]).collect();
        v.sort_by(f64::total_cmp);
        v[((q * (v.len() - 1) as f64).round() as usize).min(v.len() - 1)]
    };
    Posterior {
        q025: (0..d).map(|k| quantile(k, 0.025)).collect(),
        q975: (0..d).map(|k| quantile(k, 0.975)).collect(),
        correlation: (0..d)
            .map(|a| {
                (0..d)
                    .map(|b| cov(a, b) / (sd[a] * sd[b]).max(1e-300))
                    .collect()
            })
            .collect(),
        mean,
        sd,
        stages,
        acceptance,
        samples: x,
    }
}

//! Evaluation and training seeds: every match of an evaluation has its own
//! seed, derived from the evaluation's `--seed` and its global index, and
//! never the seed of a training match.

/// How evaluation matches get their seeds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SeedScheme {
    /// [`eval_match_seed`]: never a training match's seed.
    #[default]
    Eval,
    /// [`legacy_episode_seed`]`(seed, i, 0)`, the seed of training match
    /// `i`'s first episode before the two were separated: it replays
    /// evaluations made then.
    Legacy,
}

impl SeedScheme {
    pub fn name(self) -> &'static str {
        match self {
            SeedScheme::Eval => "eval",
            SeedScheme::Legacy => "legacy",
        }
    }

    pub fn match_seed(self, seed: u64, index: usize) -> u64 {
        match self {
            SeedScheme::Eval => eval_match_seed(seed, index),
            SeedScheme::Legacy => legacy_episode_seed(seed, index, 0),
        }
    }
}

/// The bit that tells evaluation seeds (set) from training seeds
/// (`env::episode_seed`, clear).
pub const EVAL_SEED_BIT: u64 = 1 << 63;

/// The seed of evaluation match `index` under `--seed seed`: a splitmix64
/// mix of its own (another stream constant than training's), with the top
/// bit set. Training seeds have it clear, so an evaluation never plays a
/// match any training run played, whatever the two `--seed`s.
pub fn eval_match_seed(seed: u64, index: usize) -> u64 {
    let mut z = (seed ^ 0x5EED_E7A1_0000_0000).wrapping_add(
        (index as u64)
            .wrapping_add(1)
            .wrapping_mul(0x9E37_79B9_7F4A_7C15),
    );
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    (z ^ (z >> 31)) | EVAL_SEED_BIT
}

/// The seed of training match `index`'s `episode`-th episode: a splitmix64
/// mix, so neighbouring matches and episodes get unrelated streams. Its top
/// bit is always clear: evaluation seeds ([`eval_match_seed`]) have it set,
/// so no evaluation replays a training match.
pub fn episode_seed(seed: u64, index: usize, episode: u64) -> u64 {
    legacy_episode_seed(seed, index, episode) & !EVAL_SEED_BIT
}

/// [`episode_seed`] before training and evaluation seeds were separated:
/// evaluations made then replay with it (`eval --legacy-seeds`).
pub fn legacy_episode_seed(seed: u64, index: usize, episode: u64) -> u64 {
    let mut z = seed
        ^ (index as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ episode.wrapping_mul(0xD1B5_4A32_D192_ED03);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

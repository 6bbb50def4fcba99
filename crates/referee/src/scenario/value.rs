//! The values of a scenario file: a number or a range to draw it from, and
//! a heading that may also say "face the ball" or "face the goal".

use std::fmt;

use rand::Rng;
use rand_chacha::ChaCha8Rng;
use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::Deserialize;

use super::{invalid, ScenarioError};

/// A number (`1.5`) or a range to draw it from (`[1.0, 2.0]`, uniform,
/// both ends included).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Draw {
    Fixed(f32),
    Between(f32, f32),
}

impl Default for Draw {
    fn default() -> Self {
        Draw::Fixed(0.0)
    }
}

impl Draw {
    /// The value for one start: a range takes one draw from `rng`, a
    /// number none.
    pub fn draw(self, rng: &mut ChaCha8Rng) -> f32 {
        match self {
            Draw::Fixed(v) => v,
            Draw::Between(lo, hi) if lo == hi => lo,
            Draw::Between(lo, hi) => rng.random_range(lo..=hi),
        }
    }

    /// The smallest and largest value it can take.
    pub fn bounds(self) -> (f32, f32) {
        match self {
            Draw::Fixed(v) => (v, v),
            Draw::Between(lo, hi) => (lo, hi),
        }
    }

    pub(super) fn check(self, field: &str) -> Result<(), ScenarioError> {
        let (lo, hi) = self.bounds();
        if !(lo.is_finite() && hi.is_finite()) {
            return Err(invalid(field, "is not a finite number"));
        }
        if lo > hi {
            return Err(invalid(
                field,
                format!("is [{lo}, {hi}]: a range is [low, high] with low <= high"),
            ));
        }
        Ok(())
    }
}

/// A robot's heading: radians (a number or a range), `"ball"` (facing the
/// ball) or `"goal"` (facing the centre of the goal its team attacks).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Heading {
    Angle(Draw),
    Ball,
    Goal,
}

impl Default for Heading {
    fn default() -> Self {
        Heading::Angle(Draw::Fixed(0.0))
    }
}

impl Heading {
    pub(super) fn check(self, field: &str) -> Result<(), ScenarioError> {
        match self {
            Heading::Angle(d) => d.check(field),
            Heading::Ball | Heading::Goal => Ok(()),
        }
    }
}

const DRAW: &str = "a number or a range [low, high]";
const HEADING: &str = "radians (a number or a range [low, high]), \"ball\" or \"goal\"";

/// Reads a number or `[low, high]`; with `words`, also `"ball"`/`"goal"`.
struct ValueVisitor {
    words: bool,
}

enum Value {
    Draw(Draw),
    Ball,
    Goal,
}

impl<'de> Visitor<'de> for ValueVisitor {
    type Value = Value;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(if self.words { HEADING } else { DRAW })
    }

    fn visit_f64<E: de::Error>(self, v: f64) -> Result<Value, E> {
        Ok(Value::Draw(Draw::Fixed(v as f32)))
    }

    fn visit_i64<E: de::Error>(self, v: i64) -> Result<Value, E> {
        Ok(Value::Draw(Draw::Fixed(v as f32)))
    }

    fn visit_u64<E: de::Error>(self, v: u64) -> Result<Value, E> {
        Ok(Value::Draw(Draw::Fixed(v as f32)))
    }

    fn visit_str<E: de::Error>(self, v: &str) -> Result<Value, E> {
        match v {
            "ball" if self.words => Ok(Value::Ball),
            "goal" if self.words => Ok(Value::Goal),
            _ => Err(E::invalid_value(de::Unexpected::Str(v), &self)),
        }
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Value, A::Error> {
        let wrong = |n: usize| de::Error::invalid_length(n, &"a range of two numbers [low, high]");
        let lo: f64 = seq.next_element()?.ok_or_else(|| wrong(0))?;
        let hi: f64 = seq.next_element()?.ok_or_else(|| wrong(1))?;
        if seq.next_element::<f64>()?.is_some() {
            return Err(wrong(3));
        }
        Ok(Value::Draw(Draw::Between(lo as f32, hi as f32)))
    }
}

impl<'de> Deserialize<'de> for Draw {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Draw, D::Error> {
        match d.deserialize_any(ValueVisitor { words: false })? {
            Value::Draw(v) => Ok(v),
            Value::Ball | Value::Goal => unreachable!("words are refused"),
        }
    }
}

impl<'de> Deserialize<'de> for Heading {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Heading, D::Error> {
        Ok(match d.deserialize_any(ValueVisitor { words: true })? {
            Value::Draw(v) => Heading::Angle(v),
            Value::Ball => Heading::Ball,
            Value::Goal => Heading::Goal,
        })
    }
}

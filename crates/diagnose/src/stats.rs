//! The tie rule the diagnosis's steps share (a leaf: it imports nothing of
//! the diagnosis).

/// Candidates tied with a step's winner (candidate 0, best first): those `eligible` whose
/// `score` is within `tie` (relative) of the winner's, in candidate order, and of them the
/// `simplest`, those with the fewest `columns` (the first kept, the others ambiguous with it).
pub(crate) struct Ties {
    pub within: Vec<usize>,
    pub simplest: Vec<usize>,
}

impl Ties {
    /// The tie rule of every selection step: `score[i] ≥ score[0] (1 − tie)`.
    pub(crate) fn of(
        score: &[f64],
        columns: &[usize],
        eligible: impl Fn(usize) -> bool,
        tie: f64,
    ) -> Ties {
        let within = Ties::within_of(score, eligible, tie, 0);
        let fewest = within.iter().map(|&i| columns[i]).min().unwrap_or(0);
        let simplest = within
            .iter()
            .copied()
            .filter(|&i| columns[i] == fewest)
            .collect();
        Ties { within, simplest }
    }

    /// The candidates `eligible` whose `score` is within `tie` of candidate `reference`'s:
    /// `score[i] ≥ score[reference] (1 − tie)`, in candidate order.
    pub(crate) fn within_of(
        score: &[f64],
        eligible: impl Fn(usize) -> bool,
        tie: f64,
        reference: usize,
    ) -> Vec<usize> {
        let cut = score[reference] * (1.0 - tie);
        (0..score.len())
            .filter(|&i| eligible(i) && score[i] >= cut)
            .collect()
    }

    /// The fewest columns among the tied.
    pub(crate) fn fewest(&self, columns: &[usize]) -> usize {
        columns[self.simplest[0]]
    }

    /// The tied with more columns than the simplest (set aside for it), in candidate order.
    pub(crate) fn wider<'a>(&'a self, columns: &'a [usize]) -> impl Iterator<Item = usize> + 'a {
        let fewest = self.fewest(columns);
        self.within
            .iter()
            .copied()
            .filter(move |&i| columns[i] > fewest)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ties_keep_the_fewest_columns_within_the_cut_in_candidate_order() {
        // Scores best first; candidate 3 is within the cut but not eligible.
        let score = [1.0, 0.95, 0.85, 0.99, 0.92];
        let columns = [7, 1, 1, 1, 1];
        let t = Ties::of(&score, &columns, |i| i != 3, 0.1);
        assert_eq!(t.within, vec![0, 1, 4]);
        assert_eq!(t.simplest, vec![1, 4]);
        assert_eq!(t.fewest(&columns), 1);
        assert_eq!(t.wider(&columns).collect::<Vec<_>>(), vec![0]);
        // No tie: the winner alone.
        let t = Ties::of(&score, &columns, |_| true, 0.0);
        assert_eq!((t.within, t.simplest), (vec![0], vec![0]));
    }
}

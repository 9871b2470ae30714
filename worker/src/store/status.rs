//! The states of sweeps and cases, and a case's one status word
//! ([`CaseStatus`]), each written as its serde name: the words the tables
//! store and the API serves.
use super::{StoreError, StoreResult};
use serde::{Deserialize, Serialize};
use solver::protocol::Status;

/// State of a sweep.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SweepState {
    /// Its cases are handed out to workers.
    Active,
    /// Its queued cases are not handed out; running ones no active sweep
    /// wants are handed back to the queue at their next heartbeat.
    Paused,
    /// Terminal: queued cases no other sweep wants are cancelled, running ones
    /// stop at their next heartbeat.
    Cancelled,
}

impl SweepState {
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Active => "active",
            Self::Paused => "paused",
            Self::Cancelled => "cancelled",
        }
    }
    pub fn parse(s: &str) -> StoreResult<Self> {
        [Self::Active, Self::Paused, Self::Cancelled]
            .into_iter()
            .find(|state| state.as_str() == s)
            .ok_or_else(|| StoreError::word("sweep state", s))
    }
}

/// Queue state of a case.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CaseState {
    Queued,
    Running,
    /// Has a result (whatever the solver's status).
    Done,
    /// Infrastructure failures exhausted its attempts.
    Failed,
    Cancelled,
}

impl CaseState {
    pub const ALL: [Self; 5] = [
        Self::Queued,
        Self::Running,
        Self::Done,
        Self::Failed,
        Self::Cancelled,
    ];

    pub fn as_str(self) -> &'static str {
        match self {
            Self::Queued => "queued",
            Self::Running => "running",
            Self::Done => "done",
            Self::Failed => "failed",
            Self::Cancelled => "cancelled",
        }
    }
    pub fn parse(s: &str) -> StoreResult<Self> {
        (Self::ALL.into_iter())
            .find(|state| state.as_str() == s)
            .ok_or_else(|| StoreError::word("case state", s))
    }
    pub fn is_terminal(self) -> bool {
        matches!(self, Self::Done | Self::Failed | Self::Cancelled)
    }
}

/// The one status word of a case, as the API and the metrics count it: the
/// solver's status once the case has a result (`completed`, `invalid`,
/// `diverged`, `penetrated`, `topology_changed`), its queue state before
/// (`queued`, `running`, `failed`, `cancelled`; `done` only for a result
/// gone missing). Ordered by word, as the API's counts list them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum CaseStatus {
    /// No result: the queue state (read first: `cancelled` is never a result).
    Queue(CaseState),
    /// The solver's status of the case's result (never `cancelled`).
    Result(Status),
}

impl CaseStatus {
    pub const QUEUED: Self = Self::Queue(CaseState::Queued);
    pub const RUNNING: Self = Self::Queue(CaseState::Running);
    pub const COMPLETED: Self = Self::Result(Status::Completed);

    /// Every status word, in the order the metrics list them: the queue
    /// states before a result, the solver's outcomes, then the queue's
    /// failures.
    pub fn all() -> Vec<Self> {
        let outcomes = (Status::ALL.into_iter())
            .filter(|s| *s != Status::Cancelled)
            .map(Self::Result);
        [Self::QUEUED, Self::RUNNING]
            .into_iter()
            .chain(outcomes)
            .chain([CaseState::Failed, CaseState::Cancelled].map(Self::Queue))
            .collect()
    }

    /// The status written as `word` (`Corrupt` for no status word).
    pub fn parse(word: &str) -> StoreResult<Self> {
        serde_json::from_value(serde_json::Value::from(word))
            .map_err(|_| StoreError::word("case status", word))
    }

    /// Queued or running: the case has neither a result nor an end.
    pub fn is_open(self) -> bool {
        matches!(self, Self::QUEUED | Self::RUNNING)
    }
}

impl std::fmt::Display for CaseStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        match self {
            Self::Queue(state) => f.pad(state.as_str()),
            Self::Result(status) => f.pad(&status.to_string()),
        }
    }
}

impl PartialOrd for CaseStatus {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for CaseStatus {
    /// By word (the order of the API's counts).
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.to_string().cmp(&other.to_string())
    }
}

impl From<CaseState> for CaseStatus {
    fn from(state: CaseState) -> Self {
        Self::Queue(state)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each status is written as the word it reads back from (the queue's
    /// `cancelled` for the word both enums have), and the words are distinct.
    #[test]
    fn status_words_read_back() {
        let all = CaseStatus::all();
        let words: Vec<String> = all.iter().map(|s| s.to_string()).collect();
        assert_eq!(
            words,
            [
                "queued",
                "running",
                "completed",
                "invalid",
                "diverged",
                "penetrated",
                "topology_changed",
                "failed",
                "cancelled"
            ]
        );
        for status in all {
            let json = serde_json::to_value(status).unwrap();
            assert_eq!(json, serde_json::Value::from(status.to_string()));
            assert_eq!(CaseStatus::parse(&status.to_string()).unwrap(), status);
            assert_eq!(serde_json::from_value::<CaseStatus>(json).unwrap(), status);
        }
        assert_eq!(
            CaseStatus::parse("done").unwrap(),
            CaseStatus::Queue(CaseState::Done)
        );
        assert!(matches!(
            CaseStatus::parse("finished"),
            Err(StoreError::UnknownWord { .. })
        ));
        for state in CaseState::ALL {
            assert_eq!(CaseState::parse(state.as_str()).unwrap(), state);
            assert_eq!(
                serde_json::to_value(state).unwrap(),
                serde_json::Value::from(state.as_str())
            );
        }
    }

    /// Counts keyed by status are a JSON object keyed by word, and read back.
    #[test]
    fn counts_by_status_are_objects_by_word() {
        let counts: std::collections::BTreeMap<CaseStatus, i64> =
            CaseStatus::all().into_iter().zip(1..).collect();
        let json = serde_json::to_value(&counts).unwrap();
        assert_eq!(json["topology_changed"], 7);
        assert_eq!(json["cancelled"], 9);
        assert_eq!(
            serde_json::from_value::<std::collections::BTreeMap<CaseStatus, i64>>(json).unwrap(),
            counts
        );
    }

    #[test]
    fn statuses_order_by_word() {
        let mut all = CaseStatus::all();
        all.sort();
        let words: Vec<String> = all.iter().map(|s| s.to_string()).collect();
        let mut sorted = words.clone();
        sorted.sort();
        assert_eq!(words, sorted);
    }
}

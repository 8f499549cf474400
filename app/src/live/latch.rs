//! A latched trip that survives a crash of the gateway: the `vigie-latch` thread writes
//! the latch state atomically (a temporary file, fsync, rename over `latch.json`, fsync
//! of the folder) and only then releases the events of the cycle that changed it
//! (`trip`, `reset`), so whatever the journal, stdout or the console reported is on disk
//! first. At start the gateway reads it back and restores the latch
//! ([`vigie_core::engine::Engine::restore_trip`]). The cycle never waits: it leaves the
//! new state in a mailbox (the newest state wins, the events accumulate).

use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Condvar, Mutex};
use vigie_core::engine::Trip;

/// The file's content.
#[derive(Debug, Serialize, Deserialize)]
struct LatchFile {
    /// True while a trip is latched.
    tripped: bool,
    /// The latched trip.
    trip: Option<Trip>,
}

/// What the thread writes next.
#[derive(Default)]
struct Job {
    state: Option<LatchFile>,
    events: Vec<serde_json::Value>,
    stop: bool,
}

type Mailbox = Arc<(Mutex<Job>, Condvar)>;

/// The latch store of one gateway.
pub(crate) struct LatchStore {
    mailbox: Mailbox,
    thread: Option<std::thread::JoinHandle<()>>,
}

fn file(dir: &Path) -> PathBuf {
    dir.join("latch.json")
}

/// The trip latched by an earlier run in `dir`, if any; an unreadable file is an error
/// with its line and column (the gateway does not start on a latch it cannot read).
pub(crate) fn load(dir: &Path) -> anyhow::Result<Option<Trip>> {
    let path = file(dir);
    let text = match std::fs::read_to_string(&path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => anyhow::bail!("cannot read the latched trip {}: {e}", path.display()),
    };
    let f: LatchFile = serde_json::from_str(&text).map_err(|e| {
        anyhow::anyhow!(
            "{}:{}:{}: the latched trip cannot be read ({e}); check the plant, then remove the file to start unlatched",
            path.display(),
            e.line(),
            e.column()
        )
    })?;
    Ok(if f.tripped { f.trip } else { None })
}

fn write_atomically(dir: &Path, state: &LatchFile) -> std::io::Result<()> {
    use std::io::Write as _;
    std::fs::create_dir_all(dir)?;
    let tmp = dir.join("latch.json.tmp");
    let mut f = std::fs::File::create(&tmp)?;
    f.write_all(serde_json::to_string(state).unwrap_or_default().as_bytes())?;
    f.sync_all()?;
    drop(f);
    std::fs::rename(&tmp, file(dir))?;
    std::fs::File::open(dir)?.sync_all()
}

impl LatchStore {
    /// Starts the thread writing into `dir`; it hands released events to `emit`.
    pub(crate) fn start(
        dir: PathBuf,
        mut emit: impl FnMut(serde_json::Value) + Send + 'static,
    ) -> anyhow::Result<Self> {
        std::fs::create_dir_all(&dir).map_err(|e| {
            anyhow::anyhow!("cannot create the state folder {}: {e}", dir.display())
        })?;
        let mailbox: Mailbox = Arc::default();
        let m = Arc::clone(&mailbox);
        let thread = std::thread::Builder::new()
            .name("vigie-latch".into())
            .spawn(move || {
                loop {
                    let job = {
                        let (lock, cv) = &*m;
                        let mut g = super::cycle::lock(lock);
                        while g.state.is_none() && g.events.is_empty() && !g.stop {
                            g = cv
                                .wait(g)
                                .unwrap_or_else(std::sync::PoisonError::into_inner);
                        }
                        std::mem::take(&mut *g)
                    };
                    if let Some(state) = &job.state
                        && let Err(e) = write_atomically(&dir, state)
                    {
                        tracing::error!(
                            "cannot save the latched trip in {}: {e}; a restart would forget it",
                            dir.display()
                        );
                        emit(serde_json::json!({
                            "event": "latch_not_saved", "error": e.to_string(),
                        }));
                    }
                    for e in job.events {
                        emit(e);
                    }
                    if job.stop {
                        break;
                    }
                }
            })?;
        Ok(Self {
            mailbox,
            thread: Some(thread),
        })
    }

    /// Saves the latch (`trip` while tripped), then releases `events`.
    pub(crate) fn save(&self, trip: Option<Trip>, events: Vec<serde_json::Value>) {
        let (lock, cv) = &*self.mailbox;
        let mut g = super::cycle::lock(lock);
        g.state = Some(LatchFile {
            tripped: trip.is_some(),
            trip,
        });
        g.events.extend(events);
        cv.notify_one();
    }
}

impl Drop for LatchStore {
    /// Writes what is pending, then stops the thread.
    fn drop(&mut self) {
        {
            let (lock, cv) = &*self.mailbox;
            let mut g = super::cycle::lock(lock);
            g.stop = true;
            cv.notify_one();
        }
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn trip() -> Trip {
        Trip {
            time_ms: 1234,
            cycle: 12,
            constraints: Vec::new(),
            actions: Vec::new(),
            fallback: vec![("A0".into(), false)],
            spec_error: None,
            enforced: true,
        }
    }

    #[test]
    fn a_saved_trip_is_read_back_and_a_reset_clears_it() {
        let dir = std::env::temp_dir().join(format!("vigie-latch-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        assert!(load(&dir).unwrap().is_none(), "no file: not latched");
        let (tx, rx) = std::sync::mpsc::channel();
        let store = LatchStore::start(dir.clone(), move |e| {
            let _ = tx.send(e);
        })
        .unwrap();
        store.save(Some(trip()), vec![serde_json::json!({"event": "trip"})]);
        let released = rx.recv_timeout(std::time::Duration::from_secs(10)).unwrap();
        assert_eq!(released["event"], "trip");
        // Released after the write: the file holds the trip.
        assert_eq!(load(&dir).unwrap(), Some(trip()));
        store.save(None, vec![serde_json::json!({"event": "reset"})]);
        drop(store);
        assert_eq!(rx.recv().unwrap()["event"], "reset");
        assert_eq!(load(&dir).unwrap(), None);
        std::fs::write(dir.join("latch.json"), "{\n \"tripped\": tru").unwrap();
        let err = load(&dir).unwrap_err().to_string();
        assert!(err.contains("latch.json:2:"), "{err}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}

//! The match server: listener, connections, lockstep and real-time schedulers, recording.

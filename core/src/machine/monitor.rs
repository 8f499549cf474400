//! Per-action monitor (placeholder, written on branch action-monitor).

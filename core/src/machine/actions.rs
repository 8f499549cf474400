//! Elementary actions (placeholder, written on branch action-monitor).

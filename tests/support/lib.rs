//! Shared helpers for the whole-chain tests.

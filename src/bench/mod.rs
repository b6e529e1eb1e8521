//! Device ceilings.

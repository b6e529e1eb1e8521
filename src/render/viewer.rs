//! The interactive window.

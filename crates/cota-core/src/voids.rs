//! Void filling: being written.

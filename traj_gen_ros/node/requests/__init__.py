"""A request from its subscription to its answer: thread, handler, start tick."""

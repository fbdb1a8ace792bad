"""/diagnostics: what the node reports and its publisher."""

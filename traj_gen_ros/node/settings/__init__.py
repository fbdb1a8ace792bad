"""The parameters: declared, typed, and checked together into one Config."""

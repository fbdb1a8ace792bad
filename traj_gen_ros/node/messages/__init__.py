"""What the node reads off and writes onto the wire: CDR bytes, request fields."""

"""gausspp.verification."""

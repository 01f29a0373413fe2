"""Pictures and videos of animals, creatures and learning runs (never imported by the core)."""

"""Small shared helpers: atomic file output, manifests, seeding, parallel maps."""

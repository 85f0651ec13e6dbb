"""Pictures people look at: renders, contact sheets, overlays."""

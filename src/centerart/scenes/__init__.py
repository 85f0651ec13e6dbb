"""Scenes: kitchen and single-object layouts, procedural materials and lights, cameras, SAPIEN rendering of RGB,
true and realistic depth and instance masks, and encoder labels. Entry points: ``centerart scenes generate`` and
``centerart scenes show`` (see docs/scenes.md)."""

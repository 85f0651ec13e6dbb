"""``centerart recipe``: one command from nothing to trained, evaluated models (objects -> grasp labels -> SDF
samples -> decoder -> scenes -> encoder -> closed-loop evaluation on held-out objects), resumable, with one
manifest for the whole run. Presets and step configs: :mod:`centerart.recipe.config`; the steps:
:mod:`centerart.recipe.steps`; running, skipping and the manifest: :mod:`centerart.recipe.runner`."""

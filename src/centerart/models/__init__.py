"""Neural models: the SGDF decoder (shape code + joint code + point -> SDF + grasp) and its checkpoints."""

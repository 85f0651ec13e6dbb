"""Articulated objects: the procedural generator and the loader shared with real PartNet-Mobility folders."""

from centerart.assets.articulated_object import ArticulatedObject, Joint, JointAxis, Part

__all__ = ["ArticulatedObject", "Joint", "JointAxis", "Part"]

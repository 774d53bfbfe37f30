"""Candidates of a design study and the platforms they build into."""

from .candidate import Candidate, arm_links, build_candidate, link_lengths

__all__ = ["Candidate", "arm_links", "build_candidate", "link_lengths"]

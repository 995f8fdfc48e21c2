"""Viscoplastic beams (report chapter 4): sections, the dynamic yield surface, and the
incremental elastic-viscoplastic beam element."""

"""Pictures of a run: shaded-relief previews and animations."""

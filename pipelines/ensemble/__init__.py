"""The ensemble: seating, room, master loudness and players' timing, streamed to disk."""

"""The LeRobot dataset format: the v3.0 writer and its reader, per-episode video, exact
statistics, and the v2.1 export."""

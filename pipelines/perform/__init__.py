"""Notes -> performance: instrument facts in use, the rules' events, bowing and settings."""

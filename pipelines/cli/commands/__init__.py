"""Sub-commands of the arco CLI, one module each."""

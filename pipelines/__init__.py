"""Score reading, performance rules, render/compare/evaluate jobs and the arco CLI."""

"""PyTorch reference for the VTLoc engine: model, weight export and goldens.

See README.md in this directory."""

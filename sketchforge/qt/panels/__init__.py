"""The panels around the drawing region: modes (left), controls (top right), layers and
history (bottom right). Each panel reads the document and turns its widgets' edits into commands
through the window; none keeps a copy of document state."""

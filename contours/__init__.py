"""C²-continuous NURBS neutral contours created by abstract factories (issue 5)."""

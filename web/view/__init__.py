"""The browser view: the page of a chart (placement, drawing, panels, the editor) and the
view process's end of the bus."""

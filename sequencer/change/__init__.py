"""The chart's change: edit operations and the editing session (``edit``; what every edit
shares in ``base``, edits of content and structure in ``content`` and ``structure``, texts
typed into the editor in ``typed``), what a download changes (``diff``), a GRAPH FB's state
carried across chart versions (``carry``) and online change (``online``).

Import from the module named after what it holds (``s7graph.sequencer.change.edit``).
"""

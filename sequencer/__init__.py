"""S7-GRAPH sequencers: parse, validate and compile ``.s7g`` charts, run them as engine FBs
(docs/semantics.md).

Import from the module named after what it holds — ``s7graph.sequencer.text.parse.parse_chart``,
``s7graph.sequencer.compile.compile_chart``, ``s7graph.sequencer.fb.GraphFB`` — so that a
command (``s7graph check``) loads only what it uses.
"""

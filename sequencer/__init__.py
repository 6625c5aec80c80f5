"""S7-GRAPH sequencers: parse, validate and compile ``.s7g`` charts, run them as engine FBs
(docs/semantics.md).

One sub-package per job (docs/architecture.md): the chart's text (``text``: model, grammar,
parser, writer, comments, names), its checking (``checks``: validator, rules, diagnostics),
its change (``change``: edits, diff, carry-over, online change) and ``exchange`` with other
tools; the runtime is here at the root (compile, compiled chart, cycle, fast path, FB,
state, modes, pins, display, messages, calls).

Import from the module named after what it holds — ``s7graph.sequencer.text.parse.parse_chart``,
``s7graph.sequencer.compile.compile_chart``, ``s7graph.sequencer.fb.GraphFB`` — so that a
command (``s7graph check``) loads only what it uses.
"""

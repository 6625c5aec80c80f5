"""The chart's text: the model a `.s7g` file describes (``model``), its grammar and parser
(``grammar.lark``, ``parse``; the builder ``build`` and the fast LALR loop ``lalr``), the
writer (``format``), the comments kept with their elements (``comments``), what an operand
names (``names``), where the chart calls blocks (``call_sites``), stable references to
elements (``elements``) and walking the model as data (``walk``).

Import from the module named after what it holds (``s7graph.sequencer.text.parse``).
"""

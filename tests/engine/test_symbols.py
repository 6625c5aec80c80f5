"""Symbol table (docs/runtime.md, "The block runtime", docs/architecture.md, "Seams")."""

from __future__ import annotations

from pathlib import Path

import pytest

from s7graph.engine.address import parse_address
from s7graph.engine.errors import AddressError, SymbolError
from s7graph.engine.memory import Memory
from s7graph.engine.symbols import SymbolTable


def test_semicolon_lines_give_name_address_type_comment(tmp_path: Path) -> None:
    path = tmp_path / "plant.sym"
    path.write_text('// plant\n"Start_button" ; I0.7 ; BOOL ; green button\n"Speed";MW10;INT;\n')
    table = SymbolTable.from_file(path)
    sym = table.lookup('"Start_button"')
    assert sym is not None
    assert (sym.address, sym.type, sym.comment) == (parse_address("I0.7"), "BOOL", "green button")
    assert table.resolve("Speed") == parse_address("MW10")


def test_csv_with_header_maps_columns_by_name() -> None:
    text = 'Address,Symbol,Comment,Data type\nE 0.1,Stop,"red, mushroom",BOOL\nQW2,Valve,,WORD\n'
    table = SymbolTable.from_text(text, file="io.csv")
    stop = table.lookup("Stop")
    assert stop is not None
    assert (str(stop.address), stop.type, stop.comment) == ("I0.1", "BOOL", "red, mushroom")
    assert len(table) == 2


def test_colon_entries_as_in_the_s7g_symbols_section() -> None:
    text = '  "Start_button" : I0.7 : BOOL;  "Dr_mot_on" : Q0.0 : BOOL;\n  "T_feed" : T1 : TIMER;\n'
    table = SymbolTable.from_text(text, file="drill.s7g", line=5)
    assert [s.name for s in table] == ["Start_button", "Dr_mot_on", "T_feed"]
    assert table.resolve('"T_feed"') == parse_address("T1")


def test_lookup_is_case_insensitive_and_unknown_gives_none() -> None:
    table = SymbolTable()
    table.add("Motor", "Q0.0", "BOOL")
    assert table.lookup("MOTOR") is not None
    assert table.lookup("Pump") is None


def test_duplicate_symbol_is_a_symbol_error_with_file_and_line() -> None:
    text = '"Pump" ; Q0.0 ; BOOL ; \n\n"pump" ; Q0.1 ; BOOL ;\n'
    with pytest.raises(SymbolError, match=r"^plant\.sym:3:1: duplicate symbol .*plant\.sym:1:1"):
        SymbolTable.from_text(text, file="plant.sym")


def test_unknown_type_is_a_symbol_error_with_file_and_line() -> None:
    with pytest.raises(SymbolError, match=r"^plant\.sym:2:1: .*unknown data type 'FLOAT'"):
        SymbolTable.from_text('"A" ; I0.0 ; BOOL\n"B" ; MD0 ; FLOAT\n', file="plant.sym")


def test_type_that_does_not_fit_the_address_is_a_symbol_error() -> None:
    with pytest.raises(SymbolError, match="BOOL does not fit MW0"):
        SymbolTable().add("X", "MW0", "BOOL")


def test_bad_address_in_a_colon_entry_names_its_own_line() -> None:
    text = '"A" : I0.0 : BOOL;\n"B" : I0.9 : BOOL;\n'
    with pytest.raises(SymbolError, match=r"^s\.s7g:2:1: .*I0\.9"):
        SymbolTable.from_text(text, file="s.s7g")


@pytest.mark.parametrize("sep", [";", ","])
def test_a_row_with_a_field_over_the_csv_limit_is_a_symbol_error_naming_its_line(sep: str) -> None:
    """Before: ``internal error: field larger than field limit (131072)`` in ``check``."""
    text = f'"A" {sep} I0.0 {sep} BOOL\n"B" {sep} I0.1 {sep} BOOL {sep} {"x" * 131_073}\n'
    with pytest.raises(SymbolError, match=r"^s\.sym:2:1: cannot read the row: field larger"):
        SymbolTable.from_text(text, file="s.sym")


def test_resolve_falls_back_to_absolute_addresses_but_not_for_quoted_names() -> None:
    table = SymbolTable()
    assert table.resolve_typed("MW4") == (parse_address("MW4"), "WORD")
    with pytest.raises(SymbolError, match='"Ghost"'):
        table.resolve('"Ghost"')
    with pytest.raises(AddressError):
        table.resolve("Ghost")


def test_memory_get_and_set_read_symbols_as_their_declared_type() -> None:
    mem = Memory()
    mem.symbols = SymbolTable()
    mem.symbols.add("Temp", "MW20", "INT")
    mem.set('"Temp"', -250)
    assert mem.get("Temp") == -250
    assert mem.get("MW20") == 0xFF06


def test_a_block_row_names_a_block_apart_from_the_operand_symbols() -> None:
    table = SymbolTable.from_text(
        '"Data" ; DB 20 ; DB 20 ; recipe\n"Motor" ; fb17 ; FB 17\n"Start" ; I0.0 ; BOOL\n'
    )
    data = table.block('"data"')
    assert data is not None and (data.kind, data.number, data.comment) == ("DB", 20, "recipe")
    assert [s.name for s in table] == ["Start"] and table.lookup("Data") is None
    assert table.block_names() == {"Data": "DB20", "Motor": "FB17"}
    assert table.db_number("Data") == 20 and table.db_number("Nothing") is None
    with pytest.raises(SymbolError, match='"Motor" is FB 17, not a DB'):
        table.db_number("Motor")
    with pytest.raises(SymbolError, match=r'"Start" is the operand I0\.0, not a DB'):
        table.db_number('"Start"')


def test_a_block_entry_in_the_colon_form_and_its_errors() -> None:
    table = SymbolTable.from_text('"Data" : DB20 : DB;\n"Recipe" : UDT 5 : UDT 5;\n')
    assert table.db_number("Data") == 20 and table.block_names()["Recipe"] == "UDT5"
    with pytest.raises(
        SymbolError, match=r"sym:2:1: duplicate symbol \"data\" \(first defined at sym:1:1\)"
    ):
        SymbolTable.from_text('"Data" ; DB 20\n"data" ; M0.0 ; BOOL\n', file="sym")
    with pytest.raises(SymbolError, match="block number 70000 is not 0…65535"):
        SymbolTable.from_text('"Big" ; DB 70000 ; DB\n')

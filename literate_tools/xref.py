"""Cross references between chunks: each chunk piece's number, anchor and page, and the pieces
that include each chunk (the "used in" notes of the woven pages and the index of chunks).
"""
from __future__ import annotations

import dataclasses
import re
from pathlib import Path

from literate_tools import chunks


# --------------------------------------------------------------------------------------------
# Cross references between chunks


def slug(text: str, limit: int = 60) -> str:
    """A lower-case id fragment of letters, digits and hyphens."""
    text = re.sub(r"[^a-z0-9]+", "-", text.lower()).strip("-")
    return text[:limit].rstrip("-") or "x"


def page_name(document_path: str) -> str:
    return Path(document_path).stem + ".html"


@dataclasses.dataclass
class Piece:
    """One chunk block (a definition or a continuation) as woven."""

    block: chunks.Block
    number: int  # 1-based, over all documents in reading order
    anchor: str  # the HTML id
    page: str  # the HTML file holding it
    index: int  # 0 for the definition, k for the k-th continuation


@dataclasses.dataclass
class CrossReferences:
    pieces: dict[chunks.Location, Piece]  # by the location of the opening fence
    by_name: dict[str, list[Piece]]
    uses: dict[str, list[Piece]]  # chunk name -> the pieces that include it, in reading order
    examples: dict[chunks.Location, str]  # example anchors

    def link(self, piece: Piece, from_page: str) -> str:
        return ("" if piece.page == from_page else piece.page) + "#" + piece.anchor


def cross_references(web: chunks.Web) -> CrossReferences:
    pieces: dict[chunks.Location, Piece] = {}
    by_name: dict[str, list[Piece]] = {}
    uses: dict[str, list[Piece]] = {}
    examples: dict[chunks.Location, str] = {}
    taken: set[str] = set()

    def unique(base: str) -> str:
        anchor, k = base, 2
        while anchor in taken:
            anchor, k = f"{base}-{k}", k + 1
        taken.add(anchor)
        return anchor

    number = 0
    for document in web.documents:
        for block in document.items:
            if not isinstance(block, chunks.Block):
                continue
            if block.kind == "example":
                examples[block.location] = unique("example-" + slug(block.name))
            elif block.kind == "chunk":
                number += 1
                siblings = by_name.setdefault(block.name, [])
                base = "chunk-" + slug(block.name) + (f"-{len(siblings) + 1}" if siblings else "")
                piece = Piece(block, number, unique(base), page_name(document.path), len(siblings))
                siblings.append(piece)
                pieces[block.location] = piece
    for piece in pieces.values():
        for _, _, target in chunks.references(piece.block):
            users = uses.setdefault(target, [])
            if not users or users[-1] is not piece:
                users.append(piece)
    return CrossReferences(pieces, by_name, uses, examples)


def reachable(web: chunks.Web, name: str) -> list[str]:
    """Chunk names included, directly or not, by chunk ``name`` (itself first)."""
    order, stack = [], [name]
    while stack:
        current = stack.pop()
        if current in order or current not in web.pieces:
            continue
        order.append(current)
        targets = [t for block in web.pieces[current] for _, _, t in chunks.references(block)]
        stack.extend(reversed(targets))
    return order

"""Reading text on a dial: the PP-OCR engine, where to look (regions), scale numbers, units, the number net."""

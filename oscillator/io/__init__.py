"""Files: case files (TOML) and the numbers written in them, run folders, tables read back and checked,
atomic writes and folder claims, and Ctrl-C held while a file is written whole."""

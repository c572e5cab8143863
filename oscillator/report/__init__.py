"""What a reader sees: figures in the article's style, the transition log, and the report (Markdown and
one self-contained HTML file) built from a small document model that escapes all user text."""

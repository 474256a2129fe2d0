#!/usr/bin/python3
"""Check the links of README.md and docs/**/*.md: every relative link's file exists, every
#anchor names a heading of its file (GitHub's slugs), and every "validation.md §N",
"studies.md §N" or "theory.md §N" in the repository's text names a numbered section there.
Run from anywhere: /usr/bin/python3 tools/check_doc_links.py; exit 1 on a broken link."""
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
LINK = re.compile(r'!?\[[^\]]*\]\(([^)\s]+)\)')
SECTION_REF = re.compile(r'\b(validation|studies|theory)\.md,? §(\d+(?:\.\d+)*)')


def prose_lines(text):
    """The lines outside code blocks (fenced or indented by four spaces)."""
    fenced = False
    for number, line in enumerate(text.split('\n'), 1):
        if line.lstrip().startswith('```'):
            fenced = not fenced
        elif not fenced and not line.startswith('    '):
            yield number, line


def slugs(path):
    """GitHub's anchors of the headings of a Markdown file."""
    seen, out = {}, set()
    for _, line in prose_lines(path.read_text()):
        heading = re.match(r'#{1,6} (.*)', line)
        if heading:
            slug = re.sub(r'[^\w\- ]', '', heading.group(1).strip().lower()).replace(' ', '-')
            out.add(slug if slug not in seen else f'{slug}-{seen[slug]}')
            seen[slug] = seen.get(slug, 0) + 1
    return out


def numbered_sections(path):
    return {m.group(1) for _, line in prose_lines(path.read_text())
            if (m := re.match(r'#{2,4} (\d+(?:\.\d+)*)\.? ', line))}


errors = []
for doc in [ROOT / 'README.md', *sorted((ROOT / 'docs').rglob('*.md'))]:
    for number, line in prose_lines(doc.read_text()):
        for target in LINK.findall(line):
            if re.match(r'[a-z]+:', target):
                continue  # http:, https:, mailto:
            file_part, _, anchor = target.partition('#')
            linked = (doc.parent / file_part).resolve() if file_part else doc
            where = f'{doc.relative_to(ROOT)}:{number}: {target}'
            if not linked.exists():
                errors.append(f'{where}: no such file')
            elif anchor and linked.suffix == '.md' and anchor not in slugs(linked):
                errors.append(f'{where}: no such heading')

for source in [ROOT / 'README.md', *ROOT.glob('docs/**/*.md'), *ROOT.glob('src/**/*.[ch]pp'),
               *ROOT.glob('include/**/*.hpp'), *ROOT.glob('tests/**/*.*'), *ROOT.glob('tools/**/*.py'),
               *ROOT.glob('cases/*.toml')]:
    for number, line in enumerate(source.read_text(errors='replace').split('\n'), 1):
        for name, section in SECTION_REF.findall(line):
            if section not in numbered_sections(ROOT / 'docs' / f'{name}.md'):
                errors.append(f'{source.relative_to(ROOT)}:{number}: {name}.md §{section}: no such section')

print('\n'.join(errors) if errors else 'every link, anchor and section reference resolves')
sys.exit(1 if errors else 0)

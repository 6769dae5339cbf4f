#!/usr/bin/env python3
"""Checks the README and the guide (docs/*.md) the way a reader meets them:

- every relative link and image resolves to a file of the repository, and
  every #anchor (on the same page or another) to one of its headings;
- no line of a page is 200 characters or longer;
- every `motormix ...` line shown in a shell block parses and validates
  (`motormix --parse-only ...`: options, values, files, exactly one of
  --config and --preset, the configuration it names loads, and what it
  names resolves: the scenario and each --fail of `sim`, the motor of
  `motor-test`, the --failed motors of `mix`), lines continued with a
  backslash joined first;
- and a line that needs no hardware and no bus (keygen, sign-log, matrix,
  mix, replay, import, a lockstep sim, `run --check`, `output --check`) and writes
  nowhere outside the scratch directory (no absolute path, no sudo) is then
  run as written, through the shell (so `$PWD`, `&&` and redirections are the
  reader's), and must exit 0; `mkdir` lines are carried out too;
- every `scripts/...`, `tools/...` or `python3 tools/...` line names a file
  that exists;
- the safety facts (docs/safety.md) hold everywhere: each fact there carries,
  in a comment, the words that mention it and the patterns that contradict
  it; a page whose prose (outside code blocks and tables) mentions a fact
  must link to docs/safety.md, and a sentence matching a contradiction
  fails, wherever it is.

Synopsis lines (with `[`, `|` or `...`) are reference, not commands, and are
skipped. A YAML block whose first line is `# NAME.yaml` is written to NAME.yaml
in the directory the commands run in, so a configuration shown in a page is
checked by the commands that use it; a `cp A B` line is carried out there
too. Commands run in a scratch directory that links the repository's
config/, scenarios/, test/, tools/, scripts/ and examples/.

    python3 tools/check_docs.py --motormix build/motormix [--root .]
        [--min-links N] [--min-commands N]
Exit 0 when everything resolves and at least the expected numbers of links
and commands were checked (a page that lost its examples, or a parser that
stopped finding them, fails); otherwise each failure is printed. Lines
that run a built binary (build/...) are counted as skipped, not checked.
"""

import argparse
import glob
import os
import re
import shlex
import subprocess
import sys
import tempfile

LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")


def blocks(text):
    """(language, first line number, lines) of each fenced block."""
    out, lang, start, body = [], None, 0, None
    for n, line in enumerate(text.split("\n"), 1):
        if line.startswith("```"):
            if body is None:
                lang, start, body = line[3:].strip(), n + 1, []
            else:
                out.append((lang, start, body))
                body = None
        elif body is not None:
            body.append(line)
    return out


def outside_blocks(text):
    keep, inside = [], False
    for line in text.split("\n"):
        if line.startswith("```"):
            inside = not inside
            continue
        keep.append("" if inside else line)
    return "\n".join(keep)


def slug(heading):
    """The anchor a heading gets: lower case, punctuation dropped, spaces as -."""
    text = re.sub(r"[`*_]", "", heading.strip().lstrip("#").strip()).lower()
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def anchors(text):
    return {slug(line) for line in outside_blocks(text).split("\n") if line.startswith("#")}


# Subcommands a reader can run with no hardware and no bus.
RUNNABLE = {"keygen", "sign-log", "matrix", "mix", "replay", "import"}


def runnable(words):
    if len(words) < 2 or any(w.startswith("/") for w in words[1:]):
        return False  # absolute paths: the reader's machine, not the scratch directory
    sub = words[1]
    if sub in RUNNABLE:
        return True
    if sub == "sim":
        return "--lcm" not in words
    if sub in ("run", "output"):
        return "--check" in words
    return False


def run_as_written(motormix, scratch, words, where, line=None):
    """Runs a `motormix ...` line the way a reader would, when it needs no
    hardware and no bus: [] when it exits 0, else the failure."""
    if not runnable(words):
        return []
    text = line if line is not None else " ".join(shlex.quote(w) for w in words)
    bindir = os.path.join(scratch, ".bin")
    os.makedirs(bindir, exist_ok=True)
    if not os.path.exists(os.path.join(bindir, "motormix")):
        os.symlink(motormix, os.path.join(bindir, "motormix"))
    env = dict(os.environ, PATH=bindir + os.pathsep + os.environ.get("PATH", ""))
    try:
        r = subprocess.run(["bash", "-c", text], cwd=scratch, env=env, capture_output=True,
                           text=True, timeout=120)
    except subprocess.TimeoutExpired:
        return [f"{where}: '{text}' did not finish within 120 s"]
    if r.returncode != 0:
        return [f"{where}: '{text}' exits {r.returncode}: "
                f"{(r.stderr or r.stdout).strip().splitlines()[-2:]}"]
    return []


FACT = re.compile(r"<!-- fact: ([\w-]+)\n(.*?)-->", re.S)


def safety_facts(root):
    """(name, anchor-less mention regex, [contradiction regexes]) of each fact
    in docs/safety.md; none when the page is missing."""
    path = os.path.join(root, "docs", "safety.md")
    if not os.path.exists(path):
        return []
    facts = []
    for name, body in FACT.findall(open(path).read()):
        mentions, contradicts = None, []
        for line in body.strip().split("\n"):
            key, _, value = line.partition(":")
            if key.strip() == "mentions":
                mentions = re.compile(value.strip(), re.I)
            elif key.strip() == "contradicts":
                contradicts.append(re.compile(value.strip(), re.I))
        facts.append((name, mentions, contradicts))
    return facts


def sentences(text):
    """The prose of a page (no code blocks, headings or table rows), one
    sentence at a time, with the line its paragraph starts on."""
    out, paragraph, start = [], [], 0
    for n, line in enumerate(outside_blocks(text).split("\n") + [""], 1):
        prose = line.strip() and not line.lstrip().startswith(("|", "#", "<!--"))
        if prose:
            if not paragraph:
                start = n
            paragraph.append(line.strip())
        elif paragraph:
            out += [(start, t) for t in re.split(r"(?<=[.!?])\s+", " ".join(paragraph)) if t]
            paragraph = []
    return out


def check_safety_facts(name, text, facts):
    failures = []
    if name == os.path.join("docs", "safety.md"):
        return failures
    links_here = any(os.path.basename(t.partition("#")[0]) == "safety.md"
                     for t in LINK.findall(outside_blocks(text)))
    told = set()
    for line, sentence in sentences(text):
        for fact, mentions, contradicts in facts:
            for c in contradicts:
                if c.search(sentence):
                    failures.append(f"{name}:{line}: contradicts docs/safety.md ({fact}): '{sentence[:120]}'")
            if mentions is not None and mentions.search(sentence) and not links_here and fact not in told:
                told.add(fact)
                failures.append(f"{name}:{line}: mentions {fact} but does not link to docs/safety.md")
    return failures


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--motormix", required=True)
    ap.add_argument("--root", default=os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    ap.add_argument("--min-links", type=int, default=0)
    ap.add_argument("--min-commands", type=int, default=0)
    args = ap.parse_args()
    root = os.path.abspath(args.root)
    motormix = os.path.abspath(args.motormix)
    pages = [os.path.join(root, "README.md")] + sorted(glob.glob(os.path.join(root, "docs", "*.md")))
    failures, links, commands, skipped = [], 0, 0, 0
    facts = safety_facts(root)
    if not facts:
        failures.append("docs/safety.md: no safety facts found")
    with tempfile.TemporaryDirectory() as scratch:
        for d in ("config", "scenarios", "test", "tools", "scripts", "examples"):
            os.symlink(os.path.join(root, d), os.path.join(scratch, d))
        os.makedirs(os.path.join(scratch, "out"))
        for page in pages:
            name = os.path.relpath(page, root)
            text = open(page).read()
            failures += check_safety_facts(name, text, facts)
            for n, line in enumerate(text.split("\n"), 1):
                if len(line) >= 200:
                    failures.append(f"{name}:{n}: a line of {len(line)} characters (at most 199)")
            for target in LINK.findall(outside_blocks(text)):
                if re.match(r"^(https?:|mailto:)", target):
                    continue
                links += 1
                file_part, _, anchor = target.partition("#")
                path = (page if not file_part else
                        os.path.normpath(os.path.join(os.path.dirname(page), file_part)))
                if not os.path.exists(path):
                    failures.append(f"{name}: link to {target}: no such file")
                elif anchor and path.endswith(".md") and anchor not in anchors(open(path).read()):
                    failures.append(f"{name}: link to {target}: no heading with that anchor")
            for lang, start, body in blocks(text):
                if lang == "yaml" and body and re.match(r"^# [\w.-]+\.yaml$", body[0]):
                    with open(os.path.join(scratch, body[0][2:]), "w") as f:
                        f.write("\n".join(body) + "\n")
            for lang, start, body in blocks(text):
                if lang not in ("sh", "bash", "console", ""):
                    continue
                joined, first = [], None
                for offset, line in enumerate(body):
                    if first is None:
                        first = offset
                        joined.append("")
                    joined[-1] += line.rstrip()[:-1] + " " if line.rstrip().endswith("\\") else line
                    if not line.rstrip().endswith("\\"):
                        joined[-1] = (first, joined[-1])
                        first = None
                for offset, line in [j for j in joined if isinstance(j, tuple)]:
                    line = line.strip()
                    if line.startswith("$ "):
                        line = line[2:]
                    line = re.split(r"\s+#", line, maxsplit=1)[0].strip()
                    if not line or any(s in line for s in ("[", " | ", "...")):
                        continue
                    where = f"{name}:{start + offset}"
                    try:
                        words = shlex.split(line)
                    except ValueError as e:
                        failures.append(f"{where}: cannot split '{line}': {e}")
                        continue
                    if words[0] == "sudo":
                        words = words[1:]
                    if "&&" in words:
                        # a chain: each part in turn, as the reader's shell would
                        parts, part = [], []
                        for w in words + ["&&"]:
                            if w == "&&":
                                parts.append(part)
                                part = []
                            else:
                                part.append(w)
                        words = parts[-1]
                        for p in parts[:-1]:
                            if p and p[0] == "mkdir":
                                subprocess.run(p, cwd=scratch, check=False)
                            elif p and p[0] == "motormix":
                                commands += 1
                                failures += run_as_written(motormix, scratch, p, where)
                    if words[0] == "mkdir":
                        subprocess.run(words, cwd=scratch, check=False)
                        continue
                    if words[0] == "cp" and len(words) == 3:
                        # a file the page's later commands use (its own copy)
                        subprocess.run(["cp"] + words[1:], cwd=scratch, check=False)
                        continue
                    if words[0] in ("motormix", "build/motormix", "build-release/motormix"):
                        commands += 1
                        r = subprocess.run([motormix, "--parse-only"] + words[1:], cwd=scratch,
                                           capture_output=True, text=True)
                        if r.returncode != 0:
                            failures.append(f"{where}: '{line}' is refused: "
                                            f"{(r.stderr or r.stdout).strip().splitlines()[:2]}")
                            continue
                        if words[0] == "motormix" and not line.startswith("sudo"):
                            failures += run_as_written(motormix, scratch, words, where, line)
                        continue
                    program = words[1] if words[0] in ("python3", "bash") and len(words) > 1 else words[0]
                    if program.startswith("build"):
                        skipped += 1  # produced by a build, not in the repository
                        continue
                    if program.startswith(("scripts/", "tools/", ".ci/")):
                        commands += 1
                        if not os.path.exists(os.path.join(root, program)):
                            failures.append(f"{where}: '{program}' does not exist")
    if links < args.min_links:
        failures.append(f"only {links} links checked, at least {args.min_links} expected")
    if commands < args.min_commands:
        failures.append(f"only {commands} commands checked, at least {args.min_commands} expected")
    for f in failures:
        print(f)
    print(f"check_docs: {len(pages)} pages, {links} links, {commands} commands checked, "
          f"{skipped} skipped (built binaries), {len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Writes a man page from a program's own --help (issue 14: "man pages or --help-generated docs"), so the
page never disagrees with the program. Usage:

    help_to_man.py PROGRAM SECTION SUMMARY OUT [--subcommand NAME ...] [--files FILE] [--version V]

NAME is "<program> - SUMMARY"; DESCRIPTION is `PROGRAM --help` word for word (no-fill), then each
`PROGRAM NAME --help`; FILES (optional) is FILE's text, word for word; SEE ALSO names the project's README. Exits 1 when the
program's --help fails."""
import argparse
import datetime
import os
import subprocess
import sys


def roff_escape(line):
    """Plain text as roff: backslashes doubled, a leading '.' or '\\'' kept from being a request."""
    line = line.replace("\\", "\\e")
    if line.startswith((".", "'")):
        line = "\\&" + line
    return line


def help_text(cmd):
    out = subprocess.run(cmd + ["--help"], capture_output=True, text=True, timeout=30)
    if out.returncode != 0:
        sys.exit("help_to_man: %s --help exited %d: %s" % (" ".join(cmd), out.returncode, out.stderr))
    return out.stdout


def verbatim(text):
    return ".nf\n" + "\n".join(roff_escape(l) for l in text.rstrip("\n").split("\n")) + "\n.fi\n"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("program")
    ap.add_argument("section")
    ap.add_argument("summary")
    ap.add_argument("out")
    ap.add_argument("--subcommand", action="append", default=[])
    ap.add_argument("--files", help="a text file: the FILES section")
    ap.add_argument("--version", default="")
    args = ap.parse_args()
    name = os.path.basename(args.program)
    # SOURCE_DATE_EPOCH keeps packages reproducible; otherwise today.
    epoch = int(os.environ.get("SOURCE_DATE_EPOCH", datetime.datetime.now(datetime.timezone.utc).timestamp()))
    date = datetime.datetime.fromtimestamp(epoch, datetime.timezone.utc).strftime("%Y-%m-%d")
    page = [".TH %s %s %s \"rsu-localize %s\" \"rsu-localize\"\n" % (name.upper(), args.section, date, args.version),
            ".SH NAME\n%s \\- %s\n" % (roff_escape(name), roff_escape(args.summary)),
            ".SH DESCRIPTION\nWhat \\fB%s \\-\\-help\\fR prints:\n.PP\n" % roff_escape(name),
            verbatim(help_text([args.program]))]
    for sub in args.subcommand:
        page.append(".SS %s %s\n" % (roff_escape(name), roff_escape(sub)))
        page.append(verbatim(help_text([args.program, sub])))
    if args.files:
        with open(args.files) as f:
            page.append(".SH FILES\n" + verbatim(f.read()))
    page.append(".SH SEE ALSO\nThe project's README (sections on installing, running rsud as a service, "
                "signed V2I messages, DDS and Autoware) and docs/v2i.md.\n")
    with open(args.out, "w") as f:
        f.write("".join(page))
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Writing the reports: CSV cells and files, Markdown rows and options, text files."""
import csv
import io
import os

from .mpirun import paired_medians


# ------------------------------------------------------------------------------ CSV

def csv_cell(v, list_sep=None):
    """CSV cell: floats at full precision (repr, nan as 'nan'), None empty, anything else as is;
    with `list_sep`, lists are joined by it."""
    if isinstance(v, float):
        return repr(v)
    if list_sep is not None and isinstance(v, list):
        return list_sep.join(v)
    return "" if v is None else v


def csv_text(header, rows, list_sep=None):
    """CSV text ('\\n' line ends) of a header and rows of values (see csv_cell)."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(header)
    for row in rows:
        w.writerow([csv_cell(v, list_sep) for v in row])
    return buf.getvalue()


def dict_csv_text(columns, rows):
    """CSV text (csv's default '\\r\\n' line ends) of dict rows, keys other than `columns` ignored."""
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=columns, extrasaction="ignore")
    w.writeheader()
    w.writerows(rows)
    return buf.getvalue()


def write_text(path, text):
    """Write `text` to `path` as it is (no newline translation)."""
    with open(path, "w", newline="") as fh:
        fh.write(text)


def write_atomic(path, text):
    """Write `text` to `path` through `path`.tmp, so that `path` is the old or the new file."""
    write_text(path + ".tmp", text)
    os.replace(path + ".tmp", path)


def write_csv(path, header, rows, list_sep=None):
    """A CSV file of a header and rows of values (see csv_text)."""
    write_text(path, csv_text(header, rows, list_sep))


# ------------------------------------------------------------------------------ Markdown

def md_row(cells):
    """A Markdown table row."""
    return "| " + " | ".join(cells) + " |"


def md_rule(n):
    """The rule under a Markdown table header of n columns."""
    return "|" + "|".join("---" for _ in range(n)) + "|"


def md_options(opts, files=()):
    """Options files and options as inline code (`-options_file F` `-key value`), '-' if none."""
    parts = [f"`-options_file {f}`" for f in files if f] + [f"`-{k} {v}`" for k, v in opts.items()]
    return " ".join(parts) or "-"


def write_lines(path, lines):
    """A text file of `lines`, each ended by a newline."""
    with open(path, "w") as fh:
        fh.write("\n".join(lines) + "\n")


# ------------------------------------------------------------------------------ hand-graded meshes with their own bars

def own_bars_table(runs, names, intro, tols, adaptive, pairs):
    """Markdown lines of the hand-graded meshes solved with their own bars (-bars) against -accuracy (the --hand-bars of
    scripts/accuracy_ladder.py and accuracy_remesh.py): runs, (label, command, unknowns, {name: relative bar, NaN where
    none}); names, the bars' column titles in that dict's order; adaptive, {tol: (command, unknowns, time once)}. For
    each TOL, the run with the fewest unknowns whose bars are all within TOL, timed side by side with the adaptive run
    (paired_medians(), `pairs` alternated pairs)."""
    runs = sorted(runs, key=lambda r: r[2])
    md = ["", intro, "", "| mesh | unknowns | " + " | ".join(names) + " |", md_rule(2 + len(names))]
    md += [f"| {label} | {n} | " + " | ".join(f"{v:.2%}" for v in bars.values()) + " |" for label, _, n, bars in runs]
    md += ["", "| TOL | adaptive unknowns | adaptive time (s) | fewest hand-graded unknowns with bars within TOL | its time (s) | adaptive / hand-graded |",
           md_rule(6)]
    for tol in tols:
        cmd, n_dofs, t_once = adaptive[tol]
        best = next((r for r in runs if all(v <= tol for v in r[3].values())), None)  # NaN <= tol is False
        t_ad, t_hd = paired_medians(cmd, best[1] if best else None, pairs, once=t_once)
        md.append(f"| {tol:g} | {n_dofs} | {t_ad:.2f} | " + (f"{best[0]}: {best[2]} | {t_hd:.2f} | {t_ad / t_hd:.2f} |" if best
                                                           else f"none up to {runs[-1][2]} | | |"))
    return md

"""The papers behind the scenes, cited as papers (authors, title, year, venue) wherever
user-facing text names a source.

Read from the first lines of the seed papers (shared/seeds/*.txt; scene data still says
"seed 000", `cite` turns that into the reference). Evidence for the less obvious fields: 000's DOI
10.18698/2308-6033-2024-4-2348 (Engineering Journal: Science and Innovation, 2024, no. 4);
001 says "manuscript received 05.12.2011" and cites the author's Vestnik DSTU 2011 paper, so
2012 is the publication year; 003 carries DOI 10.52684/2312-3702-2022-40-2-36-41 (2022,
no. 2(40), pp. 36-41); 004 is dated "# 05, May 2014"; 002 gives its own reference.
"""
import re

PAPERS = {
    "000": "A. A. Kiryukhin, “Numerical study of the phenomenon of the accelerated rotor drag "
           "into resonance” (Euler-vector rotor), Engineering Journal: Science and Innovation, "
           "2024, no. 4, doi:10.18698/2308-6033-2024-4-2348",
    "001": "M. V. Chuveyko, “Dynamics of rotor system spatial motion in dynamic diagnostics” "
           "(quaternion rotor model), Vestnik of Don State Technical University, 2012",
    "002": "Yao Song, Rui Xiaoting, Wang Jinghong, “Calculation of helicopter vibration in "
           "hovering state” (MSTMM), Journal of Harbin Institute of Technology, 2021, 53(6), "
           "104–111, doi:10.11918/201908100",
    "003": "O. A. Khokhlova, Ye. V. Ponomareva, A. V. Sinelshchikov, “Modification of the "
           "numerical method for solving problems of kinematic and dynamic analysis of "
           "mechanisms” (crank press), Engineering and Construction Bulletin of the Caspian "
           "Region, 2022, no. 2(40), 36–41, doi:10.52684/2312-3702-2022-40-2-36-41",
    "004": "S. M. Tenenbaum, “The mathematical model of thread unrolling from a bobbin” "
           "(solar-sail blade deployment), Science and Education (Bauman MSTU), 2014, no. 5",
}

SHORT = {"000": "Kiryukhin 2024", "001": "Chuveyko 2012", "002": "Yao, Rui, Wang 2021",
         "003": "Khokhlova, Ponomareva, Sinelshchikov 2022", "004": "Tenenbaum 2014"}

_SEED = re.compile(r"\bseeds?\s+(\d{3})\b")


def cite(text: str) -> str:
    """`text` with every "seed NNN" replaced by the paper's reference."""
    return _SEED.sub(lambda m: PAPERS.get(m.group(1), m.group(0)), text or "")


def cite_short(text: str) -> str:
    """`text` with every "seed NNN" replaced by author(s) and year (for one-line listings)."""
    return _SEED.sub(lambda m: SHORT.get(m.group(1), m.group(0)), text or "")


def papers_in(text: str) -> list[str]:
    """The references a source text names, once each."""
    return [PAPERS[n] for n in dict.fromkeys(_SEED.findall(text or "")) if n in PAPERS]

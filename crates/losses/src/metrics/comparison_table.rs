//! The Markdown table of the thesis' comparisons (Tables 5.1, 6.1, 6.2): one row per method,
//! one group of metric columns per ratio, each cell a mean, the best (lowest) value of each
//! column in bold. `pcsimplify bench` and `meshsimplify bench` print their results with it.

/// A metric column: its header and the factor its values are printed multiplied by.
#[derive(Clone, Copy, Debug)]
pub struct TableColumn<'a> {
    /// Header, e.g. `CD`; the ratio is appended (`CD @0.1`).
    pub name: &'a str,
    /// Printed value = mean × factor (e.g. 1e4 for CD in units of 10⁻⁴).
    pub factor: f64,
}

/// The table of `cell(method, ratio)` (the metrics in `columns` order, or `None` for a cell
/// without results, printed `n/a`), rows in `methods` order, three decimals. Bold marks
/// the lowest value of a column when more than one method is compared.
///
/// ```
/// use meshgnn_losses::metrics::{TableColumn, comparison_table};
/// let columns = [TableColumn { name: "CD", factor: 1.0 }];
/// let table = comparison_table(&["a", "b"], &[0.5], &columns, |m, _| Some(vec![m as f64 + 1.0]));
/// assert_eq!(table, "| method | CD @0.5 |\n|---|---:|\n| a | **1.000** |\n| b | 2.000 |\n");
/// ```
pub fn comparison_table(
    methods: &[&str],
    ratios: &[f64],
    columns: &[TableColumn],
    cell: impl Fn(usize, usize) -> Option<Vec<f64>>,
) -> String {
    let cells: Vec<Vec<Option<Vec<f64>>>> = (0..methods.len())
        .map(|m| (0..ratios.len()).map(|r| cell(m, r)).collect())
        .collect();
    let mut out = String::from("| method |");
    for ratio in ratios {
        for column in columns {
            out.push_str(&format!(" {} @{ratio} |", column.name));
        }
    }
    out.push_str("\n|---|");
    out.push_str(&"---:|".repeat(columns.len() * ratios.len()));
    out.push('\n');
    for (m, method) in methods.iter().enumerate() {
        out.push_str(&format!("| {method} |"));
        for r in 0..ratios.len() {
            for (c, column) in columns.iter().enumerate() {
                let value_of = |row: &Vec<Option<Vec<f64>>>| row[r].as_ref().map(|v| v[c]);
                let Some(value) = value_of(&cells[m]) else {
                    out.push_str(" n/a |");
                    continue;
                };
                let best = cells
                    .iter()
                    .filter_map(value_of)
                    .fold(f64::INFINITY, f64::min);
                let text = format!("{:.3}", value * column.factor);
                if value == best && methods.len() > 1 {
                    out.push_str(&format!(" **{text}** |"));
                } else {
                    out.push_str(&format!(" {text} |"));
                }
            }
        }
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_column_bolds_its_own_lowest_and_missing_cells_read_n_a() {
        let columns = [
            TableColumn {
                name: "CD",
                factor: 10.0,
            },
            TableColumn {
                name: "WA",
                factor: 1.0,
            },
        ];
        let table = comparison_table(&["x", "y"], &[0.1, 0.2], &columns, |m, r| match (m, r) {
            (0, 0) => Some(vec![0.1, 5.0]),
            (1, 0) => Some(vec![0.2, 1.0]),
            (0, 1) => Some(vec![0.3, 2.0]),
            _ => None,
        });
        let lines: Vec<&str> = table.lines().collect();
        assert_eq!(
            lines[0],
            "| method | CD @0.1 | WA @0.1 | CD @0.2 | WA @0.2 |"
        );
        assert_eq!(
            lines[2],
            "| x | **1.000** | 5.000 | **3.000** | **2.000** |"
        );
        assert_eq!(lines[3], "| y | 2.000 | **1.000** | n/a | n/a |");
        // One method: nothing is bold.
        let alone = comparison_table(&["x"], &[0.1], &columns, |_, _| Some(vec![0.1, 5.0]));
        assert!(!alone.contains("**"));
    }
}

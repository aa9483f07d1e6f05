// The index of episodes: a click on a column header sorts the rows by it (numbers by their
// data-v, text as text; n/a last), a second click the other way.
const table = document.getElementById("index");
table.querySelectorAll("th").forEach((th, col) => {
  th.style.cursor = "pointer";
  th.addEventListener("click", () => {
    const ascending = th.dataset.dir !== "asc";
    th.dataset.dir = ascending ? "asc" : "desc";
    const key = (row) => {
      const cell = row.children[col];
      return cell.dataset.v === undefined ? cell.textContent : cell.dataset.v;
    };
    const rows = [...table.tBodies[0].rows];
    rows.sort((a, b) => {
      const [x, y] = [key(a), key(b)];
      if (x === "" || y === "") return (x === "") - (y === "");
      const order = isNaN(x) || isNaN(y) ? x.localeCompare(y) : x - y;
      return ascending ? order : -order;
    });
    table.tBodies[0].append(...rows);
  });
});

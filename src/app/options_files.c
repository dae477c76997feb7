/* Before PetscInitialize(): every YAML options file named on the command line parses as YAML, or the run stops with a
   message naming the file, the line and the parser's complaint. PETSc reads the options files inside PetscInitialize()
   and, for a malformed YAML file, says only "YAML parser loading error". Plain C: PETSc is not initialized yet. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <yaml.h>
#include "app.h"

static int IsYAMLName(const char name[])
{
  const size_t n = strlen(name);

  return (n > 5 && !strcmp(name + n - 5, ".yaml")) || (n > 4 && !strcmp(name + n - 4, ".yml"));
}

/* 0 if the file parses (or cannot be opened: PETSc names a missing file itself), 1 after printing the problem. */
static int CheckYAMLFile(const char file[], int print)
{
  yaml_parser_t   parser;
  yaml_document_t doc;
  FILE           *fp = fopen(file, "rb");
  int             bad;

  if (!fp) return 0;
  if (!yaml_parser_initialize(&parser)) {
    (void)fclose(fp);
    return 0;
  }
  yaml_parser_set_input_file(&parser, fp);
  bad = !yaml_parser_load(&parser, &doc);
  if (bad && print)
    fprintf(stderr, "signorini: the options file '%s' is not valid YAML: %s at line %lu, column %lu\n", file,
            parser.problem ? parser.problem : "parse error", (unsigned long)parser.problem_mark.line + 1,
            (unsigned long)parser.problem_mark.column + 1);
  if (!bad) yaml_document_delete(&doc);
  yaml_parser_delete(&parser);
  (void)fclose(fp);
  return bad;
}

int OptionsFilesCheckYAML(int argc, char **argv)
{
  const char *rank  = getenv("OMPI_COMM_WORLD_RANK"); /* one message per run, not per rank */
  const int   print = !rank || !strcmp(rank, "0");

  for (int i = 1; i + 1 < argc; ++i) {
    const int yaml_option = !strcmp(argv[i], "-options_file_yaml");

    if ((yaml_option || (!strcmp(argv[i], "-options_file") && IsYAMLName(argv[i + 1]))) && CheckYAMLFile(argv[i + 1], print)) return 1;
  }
  return 0;
}

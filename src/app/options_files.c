/* Before PetscInitialize(): every options file named on the command line can be opened, and every YAML one parses as
   YAML, or the run stops (exit status 2, as every refusal of the input) with a message naming the file, and the line
   and the parser's complaint. PETSc reads the options files inside PetscInitialize()
   and, for a malformed YAML file, says only "YAML parser loading error". Plain C: PETSc is not initialized yet. */
#define _DEFAULT_SOURCE /* stat() under -std=c99 */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <yaml.h>
#include "app.h"

static int IsYAMLName(const char name[])
{
  const size_t n = strlen(name);

  return (n > 5 && !strcmp(name + n - 5, ".yaml")) || (n > 4 && !strcmp(name + n - 4, ".yml"));
}

/* 0 if the file can be opened, 1 after printing the problem (PETSc would stop inside PetscInitialize() with its whole
   error block and its "options not used" list). */
static int CheckReadable(const char option[], const char file[], int print)
{
  struct stat st;
  FILE       *fp;

  if (!stat(file, &st) && S_ISDIR(st.st_mode)) {
    if (print)
      fprintf(stderr, "signorini: error: %s '%s': the options file is a directory\n(-error_verbose prints PETSc's error report)\n", option, file);
    return 1;
  }
  fp = fopen(file, "rb");
  if (fp) {
    (void)fclose(fp);
    return 0;
  }
  if (print)
    fprintf(stderr, "signorini: error: %s '%s': the options file cannot be opened (%s)\n(-error_verbose prints PETSc's error report)\n", option, file,
            strerror(errno));
  return 1;
}

/* The first key given twice in one mapping of the document, from node on: its node (0: none) and the line of its first
   use. PETSc's reader keeps the last value of a key given twice without a word; a user who wrote young_modulus twice
   meant one of them. */
static int DuplicateKey(yaml_document_t *doc, yaml_node_t *node, unsigned long *first_line)
{
  if (!node) return 0;
  if (node->type == YAML_SEQUENCE_NODE)
    for (yaml_node_item_t *it = node->data.sequence.items.start; it < node->data.sequence.items.top; ++it) {
      const int dup = DuplicateKey(doc, yaml_document_get_node(doc, *it), first_line);

      if (dup) return dup;
    }
  if (node->type != YAML_MAPPING_NODE) return 0;
  for (yaml_node_pair_t *a = node->data.mapping.pairs.start; a < node->data.mapping.pairs.top; ++a) {
    yaml_node_t *ka  = yaml_document_get_node(doc, a->key);
    const int    dup = DuplicateKey(doc, yaml_document_get_node(doc, a->value), first_line);

    if (dup) return dup;
    if (!ka || ka->type != YAML_SCALAR_NODE) continue;
    for (yaml_node_pair_t *b = node->data.mapping.pairs.start; b < a; ++b) {
      yaml_node_t *kb = yaml_document_get_node(doc, b->key);

      if (kb && kb->type == YAML_SCALAR_NODE && kb->data.scalar.length == ka->data.scalar.length &&
          !memcmp(kb->data.scalar.value, ka->data.scalar.value, ka->data.scalar.length)) {
        *first_line = (unsigned long)kb->start_mark.line + 1;
        return a->key;
      }
    }
  }
  return 0;
}

/* 0 if the file parses and gives no key twice, 1 after printing the problem. */
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
    fprintf(stderr, "signorini: error: the options file '%s' is not valid YAML: %s at line %lu, column %lu\n", file,
            parser.problem ? parser.problem : "parse error", (unsigned long)parser.problem_mark.line + 1,
            (unsigned long)parser.problem_mark.column + 1);
  if (!bad) {
    unsigned long first = 0;
    const int     dup   = DuplicateKey(&doc, yaml_document_get_root_node(&doc), &first);

    if (dup) {
      yaml_node_t *key = yaml_document_get_node(&doc, dup);

      bad = 1;
      if (print)
        fprintf(stderr,
                "signorini: error: the options file '%s' gives the key '%.*s' twice, at lines %lu and %lu: PETSc would keep the second without a "
                "word; give it once\n(-error_verbose prints PETSc's error report)\n",
                file, (int)key->data.scalar.length, (const char *)key->data.scalar.value, first, (unsigned long)key->start_mark.line + 1);
    }
    yaml_document_delete(&doc);
  }
  yaml_parser_delete(&parser);
  (void)fclose(fp);
  return bad;
}

int OptionsFilesCheckYAML(int argc, char **argv)
{
  const char *rank  = getenv("OMPI_COMM_WORLD_RANK"); /* one message per run, not per rank */
  const int   print = !rank || !strcmp(rank, "0");

  for (int i = 1; i + 1 < argc; ++i) {
    const int yaml_option = !strcmp(argv[i], "-options_file_yaml"), options_file = !strcmp(argv[i], "-options_file");

    if ((yaml_option || options_file) && CheckReadable(argv[i], argv[i + 1], print)) return 1;
    if ((yaml_option || (options_file && IsYAMLName(argv[i + 1]))) && CheckYAMLFile(argv[i + 1], print)) return 1;
  }
  return 0;
}
